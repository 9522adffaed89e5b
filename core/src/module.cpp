// pinrate_core: the compiled core of pinrate (Python bindings, nanobind).
//
// Kinematics(...)                    a private Pinocchio model rebuilt from the Python model
// Servo(kinematics, ...)             the controller's settings; run(...) runs the servo loop
// spectral_radius_at(kin, ..., qs)   rho at each configuration (sample_convergence)
// solve_timing(...)                  one algorithm's solve alone, repeated (benchmarks)
//
// pinrate.compiled wraps all of this; nothing else calls it.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <chrono>
#include <string>
#include <vector>

#include "closed_form.hpp"
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

Servo make_servo(Kinematics &kinematics, const std::vector<int> &rows, const std::vector<int> &columns, int m,
                  int n_arm, int kernel, const std::vector<std::string> &measured, const std::vector<double> &row_scale,
                  double slow_threshold, bool watch, double watch_factor, double watched_step,
                  double max_linear_speed, double max_angular_speed, double dt, bool position_limits,
                  Array<const double> limits, Array<const double> rate_limits, double exact_rcond,
                  double dls_damping, bool small, const std::vector<int> &ranks, double pinv_rcond) {
  Settings s;
  s.small = small;
  if (ranks.size() != 3) throw std::invalid_argument("ranks must be (J, A, W)");
  s.rank_j = ranks[0];
  s.rank_a = ranks[1];
  s.rank_w = ranks[2];
  s.pinv_rcond = pinv_rcond;
  s.rows = rows;
  s.columns = columns;
  s.m = m;
  s.n_arm = n_arm;
  s.kernel = kernel;
  for (const std::string &name : measured) {
    s.measure_a |= name == "A";
    s.measure_w |= name == "W";
    s.measure_j |= name == "J";
  }
  s.row_scale = row_scale;
  s.slow_threshold = slow_threshold;
  s.watch = watch;
  s.watch_factor = watch_factor;
  s.watched_step = watched_step;
  s.max_linear_speed = max_linear_speed;
  s.max_angular_speed = max_angular_speed;
  s.dt = dt;
  s.position_limits = position_limits;
  // limits: (L, 4) rows of q index, v index, lower, upper; rate_limits: (R, 2) v index, limit.
  for (std::size_t i = 0; i < limits.size() / 4; ++i) {
    const double *row = limits.data() + 4 * i;
    s.limits.push_back({static_cast<int>(row[0]), static_cast<int>(row[1]), row[2], row[3]});
  }
  for (std::size_t i = 0; i < rate_limits.size() / 2; ++i) {
    const double *row = rate_limits.data() + 2 * i;
    s.rate_limits.push_back({static_cast<int>(row[0]), row[1]});
  }
  s.exact_rcond = exact_rcond;
  s.dls_damping = dls_damping;
  const int n_rows = static_cast<int>(rows.size());
  for (int index : rows)
    if (index < 0 || index >= 6) throw std::invalid_argument("row index out of range");
  for (int index : columns)
    if (index < 0 || index >= kinematics.nv()) throw std::invalid_argument("column index out of range");
  if (small && (m < 0 || m > 3 || n_rows - m > 3 || n_arm < 0 || n_arm > 3 || static_cast<int>(columns.size()) - n_arm > 3))
    throw std::invalid_argument("the closed forms take blocks of at most 3x3");
  if (m < 0 || m > n_rows || n_arm < 0 || n_arm > static_cast<int>(columns.size()))
    throw std::invalid_argument("m or n_arm out of range");
  return Servo(kinematics, std::move(s));
}

nb::tuple run_servo(Servo &servo, Array<const double> q0, Array<const double> target,
                    double gain, double tol, long stall_steps, long max_steps, double divergence_factor,
                    double stall_improvement, long step_number, double best, double progress, long progress_step,
                    Array<double> q, Array<double> rates, Array<double> position, Array<double> orientation,
                    Array<double> radius, Array<int> flags, Array<double> scale, Array<int> hit) {
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
                        stall_improvement, state, log, interrupted);
  }
  if (outcome == INTERRUPTED) throw nb::python_error();  // the signal handler's exception
  return nb::make_tuple(outcome, state.step_number, state.best, state.progress, state.progress_step);
}

// rho at each configuration (N, nq); the servo's settings give the partition. The map runs
// on a twin of the robot's kinematics (its own Data): threads sharing a Robot (a Dask worker's)
// may map at once.
void spectral_radius_at(Servo &servo, Array<const double> configurations,
                        Array<double> radii) {
  Kinematics kinematics = servo.kinematics().fresh();
  const Servo mapper(kinematics, servo.settings());
  const std::size_t count = configurations.shape(0), nq = static_cast<std::size_t>(kinematics.nq());
  if (configurations.ndim() != 2 || configurations.shape(1) != nq || radii.size() != count)
    throw std::invalid_argument("configurations must be (N, nq) and radii (N,)");
  const double *source = configurations.data();
  double *out = radii.data();
  nb::gil_scoped_release release;
  for (std::size_t i = 0; i < count; ++i) {
    kinematics.compute_jacobian(Eigen::Map<const Vector>(source + i * nq, nq));
    out[i] = mapper.radius_here();
  }
}

// Seconds per call of one block algorithm's solve on the current J (kernel names as above):
// the paper's comparison of MCA1 with the exact step, without the loop around it.
double solve_timing(Servo &servo, Array<const double> q, Array<const double> twist,
                    int kernel, long repeats) {
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
  module.doc() = "pinrate's compiled core: whole servo loops and rho maps on header-only Pinocchio";
  // pinrate keeps a Kinematics per Robot until exit; that is no leak worth a warning.
  nb::set_leak_warnings(false);
  module.attr("PINOCCHIO_VERSION") = PINOCCHIO_VERSION;
  module.attr("ABI") = 1;  // bumped when pinrate.compiled must change with it

  nb::class_<Kinematics>(module, "Kinematics")
      .def("__init__",
           [](Kinematics *self, const std::vector<std::string> &kinds, const std::vector<int> &parents,
              Array<const double> axes, Array<const double> placements, int tip_joint,
              Array<const double> tip_placement, int sensor_joint, Array<const double> sensor_placement,
              bool same_frame) {
             new (self) Kinematics(make_kinematics(kinds, parents, axes, placements, tip_joint, tip_placement,
                                                   sensor_joint, sensor_placement, same_frame));
           })
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

  nb::class_<Servo>(module, "Servo")
      .def("__init__",
           [](Servo *self, Kinematics &kinematics, const std::vector<int> &rows, const std::vector<int> &columns,
              int m, int n_arm, int kernel, const std::vector<std::string> &measured,
              const std::vector<double> &row_scale, double slow_threshold, bool watch, double watch_factor,
              double watched_step, double max_linear_speed, double max_angular_speed, double dt,
              bool position_limits, Array<const double> limits, Array<const double> rate_limits, double exact_rcond,
              double dls_damping, bool small, const std::vector<int> &ranks, double pinv_rcond) {
             new (self) Servo(make_servo(kinematics, rows, columns, m, n_arm, kernel, measured, row_scale,
                                      slow_threshold, watch, watch_factor, watched_step, max_linear_speed,
                                      max_angular_speed, dt, position_limits, limits, rate_limits, exact_rcond,
                                      dls_damping, small, ranks, pinv_rcond));
           },
           nb::keep_alive<1, 2>())
      .def("run", &run_servo)
      .def("spectral_radius_at", &spectral_radius_at)
      .def("solve_timing", &solve_timing);

  module.attr("CONVERGED") = static_cast<int>(CONVERGED);
  module.attr("DIVERGING") = static_cast<int>(DIVERGING);
  module.attr("STALLED") = static_cast<int>(STALLED);
  module.attr("MAX_STEPS") = static_cast<int>(MAX_STEPS);
  module.attr("HANDBACK") = static_cast<int>(HANDBACK);
  module.attr("FULL") = static_cast<int>(FULL);
  module.attr("SATURATED") = static_cast<int>(SATURATED);
  module.attr("RATE_LIMITED") = static_cast<int>(RATE_LIMITED_FLAG);
  module.attr("CLAMPED") = static_cast<int>(CLAMPED);
  module.attr("KERNELS") = nb::make_tuple("exact", "schur", "mca1", "mca2", "mca3", "dls");
}
