// pinrate_core: the compiled core of pinrate (Python bindings, nanobind).
//
// Kinematics(...)                    a private Pinocchio model rebuilt from the Python model
// Settings()                         the controller's settings, set field by field, by name
// Servo(kinematics, settings)        a controller's twin; run(...) runs the servo loop,
//                                    step_at(...) takes one Controller.step from q, step_given(...)
//                                    one from the caller's J
// spectral_radius_at(qs, radii, threads)  rho at each configuration (sample_convergence), on threads
// Collision(kinematics, ...)        the self-collision monitor (pinrate.control.core_collision),
//                                    passed to step_at, step_given and run
// jacobian_timing(qs, threads)       the map's Jacobians alone, timed (its bound; benchmarks)
// solve_timing(...)                  one algorithm's solve alone, repeated (benchmarks)
//
// and the constants of boundary.hpp (KERNELS, SINGULAR_RATIO, ...), which pinrate.compiled
// checks against its own when it loads the core.
//
// pinrate.compiled wraps all of this; nothing else calls it.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

// numpy's C API, this translation unit only (the per-call step reads and makes its arrays).
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "boundary.hpp"
#include "closed_form.hpp"
#include "collision.hpp"
#include "kinematics.hpp"
#include "servo.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace pinrate_core;

template <typename T>
using Array = nb::ndarray<T, nb::numpy, nb::c_contig, nb::device::cpu>;

namespace {

template <typename T>
T *data_of(Array<T> &array, std::size_t rows, const char *what) {
  if (array.shape(0) < rows) throw std::invalid_argument(std::string(what) + " has too few rows");
  return array.data();
}

Kinematics make_kinematics(const std::vector<std::string> &kinds, const std::vector<int> &parents,
                            Array<const double> axes, Array<const double> placements, int tip_joint,
                            Array<const double> tip_placement, int sensor_joint, Array<const double> sensor_placement,
                            bool same_frame) {
  if (parents.size() != kinds.size() || axes.size() != 3 * kinds.size() || placements.size() != 16 * kinds.size() ||
      tip_placement.size() != 16 || sensor_placement.size() != 16)
    throw std::invalid_argument("joint arrays of mismatched sizes");
  return Kinematics(kinds, parents, axes.data(), placements.data(), tip_joint, tip_placement.data(), sensor_joint,
                        sensor_placement.data(), same_frame);
}

// A tuple of the list's items (Python's tuple(items)).
nb::tuple tuple_of(const nb::list &items) {
  PyObject *result = PySequence_Tuple(items.ptr());
  if (!result) throw nb::python_error();
  return nb::steal<nb::tuple>(result);
}

// pinrate_core.Settings: a Settings and the names of the fields Python has set.
struct GivenSettings {
  Settings settings;
  std::set<std::string> given;
};

// Every field's name, in the order bound (pinrate_core.Settings.FIELDS).
std::vector<std::string> &settings_fields() {
  static std::vector<std::string> names;
  return names;
}

// A field of pinrate_core.Settings: a property named as ServoSettings' field, which reads and
// writes the Settings through get and set and records that it was given.
template <typename T, typename Get, typename Set>
void field(nb::class_<GivenSettings> &settings, const char *name, Get get, Set set) {
  settings_fields().push_back(name);
  settings.def_prop_rw(
      name, [get](const GivenSettings &self) { return get(self.settings); },
      [set, name](GivenSettings &self, T value) {
        set(self.settings, std::move(value));
        self.given.insert(name);
      });
}

// A field that is a Settings member of the same name and type.
template <typename T>
void member(nb::class_<GivenSettings> &settings, const char *name, T Settings::*pointer) {
  field<T>(
      settings, name, [pointer](const Settings &s) { return s.*pointer; },
      [pointer](Settings &s, T value) { s.*pointer = std::move(value); });
}

using LimitRow = std::tuple<int, int, double, double>;  // q index, v index, lower, upper
using RateLimitRow = std::tuple<int, double>;           // v index, limit

void bind_settings(nb::module_ &module) {
  nb::class_<GivenSettings> settings(module, "Settings",
                                     "A controller's settings (pinrate.compiled.ServoSettings), set by field name; "
                                     "FIELDS names them, and a Servo needs each set");
  settings.def(nb::init<>());
  member(settings, "rows", &Settings::rows);
  member(settings, "columns", &Settings::columns);
  member(settings, "m", &Settings::m);
  member(settings, "n_arm", &Settings::n_arm);
  field<std::string>(
      settings, "algorithm", [](const Settings &s) { return std::string(kKernelNames[s.kernel]); },
      [](Settings &s, const std::string &name) { s.kernel = kernel_of(name); });
  field<std::vector<std::string>>(
      settings, "measured",
      [](const Settings &s) {
        const bool measured[] = {s.measure_a, s.measure_w, s.measure_j};  // kMeasurable's order
        std::vector<std::string> names;
        for (std::size_t i = 0; i < kMeasurable.size(); ++i)
          if (measured[i]) names.emplace_back(kMeasurable[i]);
        return names;
      },
      [](Settings &s, const std::vector<std::string> &names) {
        bool *flags[] = {&s.measure_a, &s.measure_w, &s.measure_j};  // kMeasurable's order
        for (bool *flag : flags) *flag = false;
        for (const std::string &name : names) {
          std::size_t i = 0;
          while (i < kMeasurable.size() && name != kMeasurable[i]) ++i;
          if (i == kMeasurable.size()) throw std::invalid_argument("the compiled core measures no block " + name);
          *flags[i] = true;
        }
      });
  member(settings, "row_scale", &Settings::row_scale);
  member(settings, "slow_threshold", &Settings::slow_threshold);
  member(settings, "watch", &Settings::watch);
  member(settings, "watch_factor", &Settings::watch_factor);
  member(settings, "watched_step", &Settings::watched_step);
  member(settings, "max_linear_speed", &Settings::max_linear_speed);
  member(settings, "max_angular_speed", &Settings::max_angular_speed);
  member(settings, "dt", &Settings::dt);
  member(settings, "position_limits", &Settings::position_limits);
  field<std::vector<LimitRow>>(
      settings, "limits",
      [](const Settings &s) {
        std::vector<LimitRow> rows;
        for (const Limit &limit : s.limits) rows.emplace_back(limit.q_index, limit.v_index, limit.lower, limit.upper);
        return rows;
      },
      [](Settings &s, const std::vector<LimitRow> &rows) {
        s.limits.clear();
        for (const auto &[q_index, v_index, lower, upper] : rows) s.limits.push_back({q_index, v_index, lower, upper});
      });
  field<std::vector<RateLimitRow>>(
      settings, "rate_limits",
      [](const Settings &s) {
        std::vector<RateLimitRow> rows;
        for (const RateLimit &row : s.rate_limits) rows.emplace_back(row.v_index, row.limit);
        return rows;
      },
      [](Settings &s, const std::vector<RateLimitRow> &rows) {
        s.rate_limits.clear();
        for (const auto &[v_index, limit] : rows) s.rate_limits.push_back({v_index, limit});
      });
  member(settings, "exact_rcond", &Settings::exact_rcond);
  member(settings, "dls_damping", &Settings::dls_damping);
  member(settings, "small", &Settings::small);
  field<std::array<int, 3>>(
      settings, "ranks", [](const Settings &s) { return std::array<int, 3>{s.rank_j, s.rank_a, s.rank_w}; },
      [](Settings &s, const std::array<int, 3> &ranks) {  // (J, A, W)
        s.rank_j = ranks[0];
        s.rank_a = ranks[1];
        s.rank_w = ranks[2];
      });
  member(settings, "pinv_rcond", &Settings::pinv_rcond);
  nb::list names;
  for (const std::string &name : settings_fields()) names.append(name);
  settings.attr("FIELDS") = tuple_of(names);
}

Servo make_servo(Kinematics &kinematics, const GivenSettings &given) {
  for (const std::string &name : settings_fields())
    if (!given.given.count(name)) throw std::invalid_argument("pinrate_core.Settings." + name + " is not set");
  const Settings &s = given.settings;
  const int n_rows = static_cast<int>(s.rows.size()), n_columns = static_cast<int>(s.columns.size());
  for (int index : s.rows)
    if (index < 0 || index >= 6) throw std::invalid_argument("row index out of range");
  for (int index : s.columns)
    if (index < 0 || index >= kinematics.nv()) throw std::invalid_argument("column index out of range");
  if (s.small && (s.m < 0 || s.m > 3 || n_rows - s.m > 3 || s.n_arm < 0 || s.n_arm > 3 || n_columns - s.n_arm > 3))
    throw std::invalid_argument("the closed forms take blocks of at most 3x3");
  if (s.m < 0 || s.m > n_rows || s.n_arm < 0 || s.n_arm > n_columns)
    throw std::invalid_argument("m or n_arm out of range");
  if (s.measure_j && s.row_scale.size() != s.rows.size()) throw std::invalid_argument("row_scale must have a value per row");
  for (const Limit &limit : s.limits)
    if (limit.q_index < 0 || limit.q_index >= kinematics.nq() || limit.v_index < 0 || limit.v_index >= kinematics.nv())
      throw std::invalid_argument("limit index out of range");
  for (const RateLimit &row : s.rate_limits)
    if (row.v_index < 0 || row.v_index >= kinematics.nv()) throw std::invalid_argument("rate limit index out of range");
  return Servo(kinematics, s);
}

nb::tuple run_servo(Servo &servo, Array<const double> q0, Array<const double> target,
                    double gain, double tol, long stall_steps, long max_steps, double divergence_factor,
                    double stall_improvement, long step_number, double best, double progress, long progress_step,
                    Array<double> q, Array<double> rates, Array<double> position, Array<double> orientation,
                    Array<double> radius, Array<int> flags, Array<double> scale, Array<int> hit,
                    Collision *collision) {
  const int nq = servo.kinematics().nq();
  if (q0.size() != static_cast<std::size_t>(nq) || target.size() != 16) throw std::invalid_argument("q0 or target");
  const long capacity = static_cast<long>(flags.shape(0));
  ServoLog log{data_of(q, capacity + 1, "q"),
               data_of(rates, capacity, "rates"),
               data_of(position, capacity + 1, "position"),
               data_of(orientation, capacity + 1, "orientation"),
               data_of(radius, capacity + 1, "radius"),
               flags.data(),
               data_of(scale, capacity, "scale"),
               data_of(hit, capacity, "hit"),
               capacity};
  ServoState state{step_number, best, progress, progress_step};
  const Eigen::Map<const Vector> start(q0.data(), nq);
  // Ctrl-C reaches a long run: every few thousand steps the loop takes the GIL and asks.
  const auto interrupted = []() {
    nb::gil_scoped_acquire gil;
    return PyErr_CheckSignals() != 0;
  };
  int outcome;
  {
    nb::gil_scoped_release release;
    outcome = servo.run(start, se3_from(target.data()), gain, tol, stall_steps, max_steps, divergence_factor,
                        stall_improvement, state, log, interrupted, collision);
  }
  if (outcome == INTERRUPTED) throw nb::python_error();  // the signal handler's exception
  return nb::make_tuple(outcome, state.step_number, state.best, state.progress, state.progress_step);
}

// numpy arrays in and out of the per-call step, through numpy's C API: a step costs about a
// microsecond, and nanobind's ndarray casters cost a fifth of that per array.

// The array behind object when it is a float64 array of the given shape (columns 0: 1-D;
// the exact numpy.ndarray type, aligned, native byte order, any strides), else nullptr: the
// caller hands the step to Python's checks, which convert or refuse what this does not read.
PyArrayObject *float_array(PyObject *object, npy_intp rows, npy_intp columns = 0) {
  if (Py_TYPE(object) != &PyArray_Type) return nullptr;
  auto *array = reinterpret_cast<PyArrayObject *>(object);
  const int ndim = columns ? 2 : 1;
  if (PyArray_NDIM(array) != ndim || PyArray_TYPE(array) != NPY_DOUBLE || !PyArray_ISBEHAVED_RO(array) ||
      PyArray_DIM(array, 0) != rows || (columns && PyArray_DIM(array, 1) != columns))
    return nullptr;
  return array;
}

// array[i] (1-D) and array[r, c] (2-D) whatever the strides.
double item(PyArrayObject *array, npy_intp i) {
  return *reinterpret_cast<const double *>(PyArray_BYTES(array) + i * PyArray_STRIDE(array, 0));
}
double item(PyArrayObject *array, npy_intp r, npy_intp c) {
  return *reinterpret_cast<const double *>(PyArray_BYTES(array) + r * PyArray_STRIDE(array, 0) +
                                           c * PyArray_STRIDE(array, 1));
}

// A new float64 array of n entries (owned by the caller), its data.
nb::object new_vector(npy_intp n, double *&data) {
  PyObject *array = PyArray_SimpleNew(1, &n, NPY_DOUBLE);
  if (!array) throw nb::python_error();
  data = static_cast<double *>(PyArray_DATA(reinterpret_cast<PyArrayObject *>(array)));
  return nb::steal(array);
}

nb::object copy_of(const Vector &vector) {
  double *data;
  nb::object array = new_vector(vector.size(), data);
  std::copy(vector.data(), vector.data() + vector.size(), data);
  return array;
}

// q (nq,) of the caller into the servo's working q, when readable; nullptr else.
const Vector *read_q(Servo &servo, PyObject *q_object) {
  Vector &q = servo.working_q();
  PyArrayObject *array = float_array(q_object, q.size());
  if (!array) return nullptr;
  for (npy_intp i = 0; i < q.size(); ++i) q[i] = item(array, i);
  return &q;
}

// The twist command (m + k,) into a new array, when readable and check_vector would pass it.
nb::object read_twist(Servo &servo, PyObject *twist_object, double *&twist) {
  const npy_intp n = static_cast<npy_intp>(servo.settings().rows.size());
  PyArrayObject *array = float_array(twist_object, n);
  if (!array) return nb::none();
  nb::object copy = new_vector(n, twist);
  for (npy_intp i = 0; i < n; ++i) twist[i] = item(array, i);
  if (!servo.admits_twist(twist)) return nb::none();
  return copy;
}

// A step the core took: (flags, scale, hit, next q (nq,), rates (nv,), twist (m + k,), seen),
// each array the caller's own.
nb::tuple taken_step(const Servo &servo, const Taken &taken, nb::object twist, nb::object seen) {
  return nb::make_tuple(taken.flags, taken.scale, taken.hit, copy_of(servo.next()), copy_of(servo.rates()),
                        std::move(twist), std::move(seen));
}

// What the kinematics pass saw (J row-major (6, nv), then world_T_tip and world_T_sensor as
// a row-major rotation and a translation each: 6 nv + 24 entries), for the step's Observation.
nb::object seen(const Kinematics &kinematics) {
  const npy_intp nv = kinematics.nv();
  double *data;
  nb::object array = new_vector(6 * nv + 24, data);
  for (int r = 0; r < 6; ++r)
    for (npy_intp c = 0; c < nv; ++c) *data++ = kinematics.jacobian(r, c);
  for (const SE3 *pose : {&kinematics.world_T_tip, &kinematics.world_T_sensor}) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) *data++ = pose->rotation()(r, c);
    for (int r = 0; r < 3; ++r) *data++ = pose->translation()[r];
  }
  return array;
}

// One Controller.step from Python with everything Python does before and in it (see
// pinrate.control.core_step): q checked as Robot.check_q and check_inside_limits check it, the
// twist as check_vector does (or, target given (4, 4), gain times the pose error to it), the
// kinematics pass, advance. None where Python must check the inputs (an input not a float
// array of its shape, or one its checks refuse: they say what is wrong), False where the step
// is Python's; else taken_step's tuple, seen what the pass saw.
nb::object step_at(Servo &servo, nb::handle q_object, nb::handle command, nb::handle target_object, double gain,
                   Collision *collision) {
  const Vector *q = read_q(servo, q_object.ptr());
  if (!q) return nb::none();
  double *twist;
  nb::object twist_array;
  SE3 target;
  const bool pose = !target_object.is_none();
  if (pose) {
    PyArrayObject *homogeneous = float_array(target_object.ptr(), 4, 4);
    if (!homogeneous) return nb::none();
    Eigen::Matrix3d rotation;
    Eigen::Vector3d translation;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation(r, c) = item(homogeneous, r, c);
      translation[r] = item(homogeneous, r, 3);
    }
    target = SE3(rotation, translation);
    twist_array = new_vector(static_cast<npy_intp>(servo.settings().rows.size()), twist);
  } else {
    twist_array = read_twist(servo, command.ptr(), twist);
    if (twist_array.is_none()) return twist_array;
  }
  if (!servo.admits(*q)) return nb::none();
  Taken taken;
  if (!servo.step_at(*q, pose ? &target : nullptr, gain, twist, taken, collision)) return nb::bool_(false);
  return taken_step(servo, taken, std::move(twist_array), seen(servo.kinematics()));
}

// One Controller.step from the caller's Observation (q (nq,) and J (6, nv), sensor axes, any
// strides) and twist (m + k,): q inside the limits, the twist checked, advance. None, False or
// taken_step's tuple (seen None: the caller has its Observation), as step_at.
nb::object step_given(Servo &servo, nb::handle q_object, nb::handle jacobian_object, nb::handle command,
                      Collision *collision) {
  const Vector *q = read_q(servo, q_object.ptr());
  Kinematics &kinematics = servo.kinematics();
  PyArrayObject *jacobian = float_array(jacobian_object.ptr(), 6, kinematics.nv());
  if (!q || !jacobian) return nb::none();
  double *twist;
  nb::object twist_array = read_twist(servo, command.ptr(), twist);
  if (twist_array.is_none() || !servo.admits(*q)) return nb::none();
  for (npy_intp c = 0; c < kinematics.nv(); ++c)
    for (int r = 0; r < 6; ++r) kinematics.jacobian(r, c) = item(jacobian, r, c);
  Taken taken;
  if (!servo.step_from_jacobian(*q, twist, taken, collision)) return nb::bool_(false);
  return taken_step(servo, taken, std::move(twist_array), nb::none());
}

// --- the self-collision monitor ----------------------------------------------------------

// pinrate_core.Collision: geometry g (of the monitor's geometry model, in its order) is kinds[g]
// with numbers[g] (and triangles[g] for a mesh) on joint joints[g] at placements[g] (G, 4, 4;
// row-major homogeneous, in the joint's frame); pair i is (firsts[i], seconds[i]), its GJK
// started from guesses[i].
Collision make_collision(const Kinematics &kinematics, const std::vector<std::string> &kinds,
                         const std::vector<std::vector<double>> &numbers,
                         const std::vector<std::vector<long>> &triangles, const std::vector<int> &joints,
                         Array<const double> placements, const std::vector<int> &firsts,
                         const std::vector<int> &seconds, const std::vector<coal::GJKInitialGuess> &guesses,
                         const CollisionRules &rules) {
  const std::size_t count = kinds.size();
  if (numbers.size() != count || triangles.size() != count || joints.size() != count ||
      placements.size() != 16 * count)
    throw std::invalid_argument("geometry arrays of mismatched sizes");
  std::vector<std::shared_ptr<coal::CollisionGeometry>> geometries;
  std::vector<SE3> poses;
  for (std::size_t g = 0; g < count; ++g) {
    geometries.push_back(make_geometry(kinds[g], numbers[g], triangles[g]));
    poses.push_back(se3_from(placements.data() + 16 * g));
  }
  return Collision(kinematics, std::move(geometries), joints, std::move(poses), firsts, seconds, guesses, rules);
}

// --- the rho map (sample_convergence) and its bound ---------------------------------------
// Kept apart from the servo's bindings above: only this block and NB_MODULE's two lines for it
// belong to the map.

// work(kinematics, mapper, begin, end) over `threads` contiguous chunks of [0, count), each on
// a thread of its own with a twin of the servo's kinematics (its own Data and J; the model,
// read-only, copied), so threads sharing a Robot (a Dask worker's) may map at once too. The
// split changes only which thread takes a configuration, never the operations made on it.
// Runs without the GIL; the caller's thread takes the first chunk.
template <typename Work>
void over_chunks(const Servo &servo, std::size_t count, long threads, const Work &work) {
  const std::size_t used = static_cast<std::size_t>(std::max(1L, std::min(threads, static_cast<long>(count))));
  std::vector<std::exception_ptr> errors(used);
  const auto chunk = [&](std::size_t t) {
    try {
      Kinematics kinematics = servo.kinematics().fresh();
      const Servo mapper(kinematics, servo.settings());
      work(kinematics, mapper, count * t / used, count * (t + 1) / used);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  nb::gil_scoped_release release;
  std::vector<std::thread> pool;
  pool.reserve(used - 1);
  for (std::size_t t = 1; t < used; ++t) pool.emplace_back(chunk, t);
  chunk(0);
  for (std::thread &thread : pool) thread.join();
  for (const std::exception_ptr &error : errors)
    if (error) std::rethrow_exception(error);
}

std::size_t checked_count(const Servo &servo, const Array<const double> &configurations, long threads) {
  const std::size_t nq = static_cast<std::size_t>(servo.kinematics().nq());
  if (configurations.ndim() != 2 || configurations.shape(1) != nq)
    throw std::invalid_argument("configurations must be (N, nq)");
  if (threads < 1) throw std::invalid_argument("threads must be at least 1");
  return configurations.shape(0);
}

// rho at each configuration (N, nq) into radii (N,), over `threads` threads; the servo's
// settings give the partition. Per q: J (the map's kinematics pass), the blocks read straight
// from J's storage at offsets found once, the closed forms (general.hpp's on the stack for a
// partition of up to kCapped joints); nothing allocated per q.
void spectral_radius_at(Servo &servo, Array<const double> configurations, Array<double> radii, long threads) {
  const std::size_t count = checked_count(servo, configurations, threads);
  if (radii.size() != count) throw std::invalid_argument("radii must be (N,)");
  const double *source = configurations.data();
  double *out = radii.data();
  const int nq = servo.kinematics().nq();
  const Settings &s = servo.settings();
  const int n = static_cast<int>(s.columns.size()), m = s.m, k = static_cast<int>(s.rows.size()) - s.m;
  const bool capped = !s.small && n <= kCapped;
  const BlockLayout layout = s.small ? BlockLayout(s.rows.data(), s.columns.data(), m, k, s.n_arm, n) : BlockLayout();
  over_chunks(servo, count, threads,
              [&](Kinematics &kinematics, const Servo &mapper, std::size_t begin, std::size_t end) {
                Blocks b;
                const int n_wrist = n - s.n_arm;
                Capped A(m, s.n_arm), B(m, n_wrist), U(k, s.n_arm), W(k, n_wrist);  // sized once
                for (std::size_t i = begin; i < end; ++i) {
                  kinematics.compute_jacobian(Eigen::Map<const Vector>(source + i * nq, nq));
                  const double *J = kinematics.jacobian.data();  // column-major, 6 rows
                  if (s.small) {
                    layout.gather(J, b.A, b.B, b.U, b.W);
                    out[i] = Servo::radius_of(b);
                  } else if (capped) {
                    for (int c = 0; c < n; ++c) {
                      const double *column = J + 6 * s.columns[c];
                      for (int r = 0; r < m + k; ++r) {
                        const double value = column[s.rows[r]];
                        if (c < s.n_arm)
                          (r < m ? A(r, c) : U(r - m, c)) = value;
                        else
                          (r < m ? B(r, c - s.n_arm) : W(r - m, c - s.n_arm)) = value;
                      }
                    }
                    out[i] = block_spectral_radius<Capped>(A, B, U, W, s.pinv_rcond);
                  } else {
                    out[i] = mapper.radius_here();
                  }
                }
              });
}

// Seconds (wall clock) for the map's Jacobians alone at each configuration (N, nq) over
// `threads` threads, split as spectral_radius_at splits them: the bound a rho map cannot beat
// (benchmarks/region_map.py), the twins' set-up included as it is in the map.
double jacobian_timing(Servo &servo, Array<const double> configurations, long threads) {
  const std::size_t count = checked_count(servo, configurations, threads);
  const double *source = configurations.data();
  const int nq = servo.kinematics().nq();
  double sinks = 0.0;
  std::mutex guard;
  const auto start = std::chrono::steady_clock::now();
  over_chunks(servo, count, threads, [&](Kinematics &kinematics, const Servo &, std::size_t begin, std::size_t end) {
    double sink = 0.0;  // one element of each J, so no J goes unused
    for (std::size_t i = begin; i < end; ++i) {
      kinematics.compute_jacobian(Eigen::Map<const Vector>(source + i * nq, nq));
      sink = sink + kinematics.jacobian(0, 0);
    }
    const std::lock_guard<std::mutex> lock(guard);
    sinks = sinks + sink;
  });
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
  volatile double kept = sinks;
  static_cast<void>(kept);
  return elapsed.count();
}

// Seconds per call of one block algorithm's solve on the current J (kernel names as above):
// the paper's comparison of MCA1 with the exact step, without the loop around it.
double solve_timing(Servo &servo, Array<const double> q, Array<const double> twist,
                    const std::string &algorithm, long repeats) {
  const Kernel kernel = kernel_of(algorithm);
  if (kernel != EXACT && kernel != MCA1 && kernel != MCA2)
    throw std::invalid_argument("solve_timing times exact, mca1 or mca2, not " + algorithm);
  Kinematics &kinematics = servo.kinematics();
  kinematics.compute(Eigen::Map<const Vector>(q.data(), kinematics.nq()));
  const Blocks b = servo.blocks();
  Vec3 v, omega;
  const int n_rows = static_cast<int>(twist.size());
  v.n = b.A.rows;
  omega.n = n_rows - b.A.rows;
  for (int r = 0; r < v.n; ++r) v[r] = twist.data()[r];
  for (int r = 0; r < omega.n; ++r) omega[r] = twist.data()[v.n + r];
  Eigen::MatrixXd J(n_rows, servo.n());
  for (int r = 0; r < n_rows; ++r) {
    for (int c = 0; c < b.A.cols; ++c) J(r, c) = r < v.n ? b.A(r, c) : b.U(r - v.n, c);
    for (int c = b.A.cols; c < servo.n(); ++c) J(r, c) = r < v.n ? b.B(r, c - b.A.cols) : b.W(r - v.n, c - b.A.cols);
  }
  const Eigen::VectorXd command = Eigen::Map<const Eigen::VectorXd>(twist.data(), n_rows);
  volatile double sink = 0.0;  // keeps the work
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < repeats; ++i) {
    if (kernel == EXACT) {
      sink = sink + J.partialPivLu().solve(command)[0];
    } else {
      const Rates rates = kernel == MCA1 ? mca1(b.A, b.B, b.U, b.W, v, omega) : mca2(b.A, b.B, b.U, b.W, v, omega);
      sink = sink + rates.arm[0];
    }
  }
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
  return elapsed.count() / static_cast<double>(repeats);
}

}  // namespace

NB_MODULE(pinrate_core, module) {
  if (PyArray_ImportNumPyAPI() < 0) throw nb::python_error();
  module.doc() = "pinrate's compiled core: whole servo loops and rho maps on header-only Pinocchio";
  // pinrate keeps a Kinematics per Robot until exit; that is no leak worth a warning.
  nb::set_leak_warnings(false);
  module.attr("PINOCCHIO_VERSION") = PINOCCHIO_VERSION;
  module.attr("ABI") = 7;  // bumped when pinrate.compiled must change with it
  module.attr("COAL_VERSION") = COAL_VERSION;  // the coal headers and libcoal the core was built on

  // boundary.hpp's constants, which pinrate.compiled.boundary checks at load.
  module.attr("SINGULAR_RATIO") = kSingularRatio;
  module.attr("FLAT") = kFlat;
  module.attr("PHYSICAL_BOUND") = kPhysicalBound;
  module.attr("UNIT_TOLERANCE") = kUnitTolerance;
  nb::list kernels, outcomes, measurable, joint_kinds_list;
  for (const char *name : kKernelNames) kernels.append(name);
  module.attr("KERNELS") = tuple_of(kernels);
  for (std::size_t value = 0; value < kOutcomeNames.size(); ++value) {
    outcomes.append(kOutcomeNames[value]);
    module.attr(kOutcomeNames[value]) = static_cast<int>(value);
  }
  module.attr("OUTCOMES") = tuple_of(outcomes);  // by value
  nb::dict step_flags;
  for (const NamedFlag &flag : kStepFlags) {
    step_flags[flag.name] = flag.value;
    module.attr(flag.name) = flag.value;
  }
  module.attr("STEP_FLAGS") = step_flags;
  for (const char *name : kMeasurable) measurable.append(name);
  module.attr("MEASURABLE") = tuple_of(measurable);
  for (const JointKind &kind : joint_kinds()) joint_kinds_list.append(kind.name);
  module.attr("JOINT_KINDS") = tuple_of(joint_kinds_list);

  nb::class_<Kinematics>(module, "Kinematics")
      .def("__init__",
           [](Kinematics *self, const std::vector<std::string> &kinds, const std::vector<int> &parents,
              Array<const double> axes, Array<const double> placements, int tip_joint,
              Array<const double> tip_placement, int sensor_joint, Array<const double> sensor_placement,
              bool same_frame) {
             new (self) Kinematics(make_kinematics(kinds, parents, axes, placements, tip_joint, tip_placement,
                                                   sensor_joint, sensor_placement, same_frame));
           },
           nb::kw_only(), "kinds"_a, "parents"_a, "axes"_a, "placements"_a, "tip_joint"_a, "tip_placement"_a,
           "sensor_joint"_a, "sensor_placement"_a, "same_frame"_a)
      .def_prop_ro("nq", &Kinematics::nq)
      .def_prop_ro("nv", &Kinematics::nv)
      .def(
          "jacobian",
          [](Kinematics &self, Array<const double> q) {
            if (q.size() != static_cast<std::size_t>(self.nq())) throw std::invalid_argument("q has the wrong size");
            self.compute(Eigen::Map<const Vector>(q.data(), self.nq()));
            auto *copy = new Eigen::MatrixXd(self.jacobian);  // column-major (6, nv)
            nb::capsule owner(copy, [](void *p) noexcept { delete static_cast<Eigen::MatrixXd *>(p); });
            return nb::ndarray<nb::numpy, double, nb::ndim<2>>(copy->data(), {6, static_cast<std::size_t>(self.nv())},
                                                               owner, {1, 6});
          },
          "q"_a, "J in the sensor frame's axes (6, nv) at q");

  bind_settings(module);

  nb::class_<Collision>(module, "Collision")
      .def("__init__",
           [](Collision *self, const Kinematics &kinematics, const std::vector<std::string> &kinds,
              const std::vector<std::vector<double>> &numbers, const std::vector<std::vector<long>> &triangles,
              const std::vector<int> &joints, Array<const double> placements, const std::vector<int> &firsts,
              const std::vector<int> &seconds, double safety_distance, double stop_distance, double approach_speed,
              double halt_scale, double coincident, double gjk_tolerance, bool cached_gjk_guess,
              const std::vector<std::string> &gjk_initial_guesses) {
             const CollisionRules rules{safety_distance, stop_distance, approach_speed, halt_scale,
                                        coincident,      gjk_tolerance, cached_gjk_guess};
             std::vector<coal::GJKInitialGuess> guesses;
             for (const std::string &name : gjk_initial_guesses) guesses.push_back(gjk_guess_of(name));
             new (self) Collision(make_collision(kinematics, kinds, numbers, triangles, joints, placements, firsts,
                                                 seconds, guesses, rules));
           },
           nb::kw_only(), "kinematics"_a, "kinds"_a, "numbers"_a, "triangles"_a, "joints"_a, "placements"_a,
           "firsts"_a, "seconds"_a, "safety_distance"_a, "stop_distance"_a, "approach_speed"_a, "halt_scale"_a,
           "coincident"_a, "gjk_tolerance"_a, "cached_gjk_guess"_a, "gjk_initial_guesses"_a)
      .def_prop_ro("pair_count", &Collision::pair_count)
      .def(
          "last",
          [](const Collision &self) {
            const CollisionVerdict &verdict = self.last();
            return nb::make_tuple(verdict.kind, verdict.scale, verdict.pair, verdict.distance);
          },
          "(kind, scale, pair, distance) of the last verdict: kind 0 clear, 1 slowed, 2 halted")
      .def(
          "limit",
          [](Collision &self, Array<const double> q, Array<const double> rates, double dt) {
            if (q.size() != static_cast<std::size_t>(self.nq()) || rates.size() != static_cast<std::size_t>(self.nv()))
              throw std::invalid_argument("q must be (nq,) and rates (nv,)");
            const CollisionVerdict verdict =
                self.limit(Eigen::Map<const Vector>(q.data(), q.size()), Eigen::Map<const Vector>(rates.data(), rates.size()), dt);
            return nb::make_tuple(verdict.kind, verdict.scale, verdict.pair, verdict.distance);
          },
          "q"_a, "rates"_a, "dt"_a, "CollisionMonitor.limit's verdict as (kind, scale, pair, distance)")
      .def(
          "distances",
          [](Collision &self, Array<const double> q) {
            if (q.size() != static_cast<std::size_t>(self.nq())) throw std::invalid_argument("q must be (nq,)");
            return self.distances_at(Eigen::Map<const Vector>(q.data(), q.size()));
          },
          "q"_a, "every pair's distance (m) at q");

  nb::class_<Servo>(module, "Servo")
      .def("__init__",
           [](Servo *self, Kinematics &kinematics, const GivenSettings &settings) {
             new (self) Servo(make_servo(kinematics, settings));
           },
           "kinematics"_a, "settings"_a, nb::keep_alive<1, 2>())
      .def("run", &run_servo, nb::kw_only(), "q0"_a, "target"_a, "gain"_a, "tol"_a, "stall_steps"_a, "max_steps"_a,
           "divergence_factor"_a, "stall_improvement"_a, "step_number"_a, "best"_a, "progress"_a, "progress_step"_a,
           "q"_a, "rates"_a, "position"_a, "orientation"_a, "radius"_a, "flags"_a, "scale"_a, "hit"_a,
           "collision"_a.none() = nb::none())
      // .none(): any object reaches the step (None included), which reads what it can.
      .def("step_at", &step_at, "q"_a.none(), "twist"_a.none(), "target"_a.none(), "gain"_a,
           "collision"_a.none() = nb::none())
      .def("step_given", &step_given, "q"_a.none(), "jacobian"_a.none(), "twist"_a.none(),
           "collision"_a.none() = nb::none())
      .def("spectral_radius_at", &spectral_radius_at, "configurations"_a, "radii"_a, "threads"_a = 1)
      .def("jacobian_timing", &jacobian_timing, "configurations"_a, "threads"_a = 1)
      .def("solve_timing", &solve_timing);
}
