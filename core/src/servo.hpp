// pinrate.control.Controller.step and pinrate.control.servo_loop.servo as one C++ loop.
//
// The loop runs the step's common path: kinematics, pose error, saturation, the conditioning
// bound, the algorithm, the position-limit test, the velocity-limit scale, integration and
// the clamp, and the servo's stop rules. Whatever needs more (the singular region, a joint
// passing a limit, a singular block, a step the decelerate rule must judge one step ahead,
// a least-squares exact step) is handed back: the Python controller takes that one step and
// the loop goes on. So each rule is written once in full (in Python) and the common path
// twice (here, and there), and the test of the two paths holds them together.
//
// That common path is one member, advance(), which the loop runs each step and step_at() runs
// for a single Controller.step called from Python (pinrate.control.core_step), with the same
// hand-back, after the checks Python makes before a step (admits, admits_twist).
#pragma once

#include <Eigen/LU>
#include <cmath>
#include <algorithm>
#include <functional>
#include <vector>

#include "boundary.hpp"
#include "closed_form.hpp"
#include "collision.hpp"
#include "general.hpp"
#include "kinematics.hpp"

namespace pinrate_core {

// Steps between two looks at the caller's signals (Ctrl-C): about 5 ms of loop.
constexpr long kSignalCheckSteps = 4096;

struct Limit {
  int q_index, v_index;
  double lower, upper;
};

struct RateLimit {
  int v_index;
  double limit;
};

// The controller's settings, from pinrate.control.Controller: module.cpp binds them as
// pinrate_core.Settings, which pinrate.compiled fills from ServoSettings field by field, by
// name. No defaults here: every field is set from Python (a Servo is refused while one is not).
struct Settings {
  std::vector<int> rows;     // the twist's rows of J, partition order (m linear first)
  std::vector<int> columns;  // velocity indices of the partition's joints, arm then wrist
  int m{}, n_arm{};
  Kernel kernel{};  // set by name (the field "algorithm")
  bool measure_a{}, measure_w{}, measure_j{};  // set by letter (the field "measured")
  std::vector<double> row_scale;  // (m + k,)
  double slow_threshold{}, watch_factor{}, watched_step{};
  bool watch{};  // singularity="decelerate" (or auxiliary_elbow): judge big steps near the region
  double max_linear_speed{}, max_angular_speed{}, dt{};
  bool position_limits{};
  std::vector<Limit> limits;
  std::vector<RateLimit> rate_limits;
  double exact_rcond{}, dls_damping{};
  bool small{};  // A and W square of size <= 3: the closed forms; else general.hpp
  int rank_j{}, rank_a{}, rank_w{};  // generic ranks (the field "ranks"): c is sigma_rank / sigma_1
  double pinv_rcond{};
};

// A square block of J of at most 6 x 6 (a square reduced J), kept on the stack: Eigen's
// LU and inverse make the same operations as on an Eigen::MatrixXd, without the allocations.
using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

struct Blocks {
  Block A, B, U, W;
};

// What a step the core took met (boundary.hpp's StepFlag), its velocity scale (1 for none)
// and the first limit it clamped (-1 for none).
struct Taken {
  int flags = 0;
  double scale = 1.0;
  int hit = -1;
};

// The servo's stop-rule state, carried across hand-backs.
struct ServoState {
  long step_number = 0;
  double best = INFINITY, progress = INFINITY;
  long progress_step = 0;
};

// One run's arrays (rows indexed by step number), written in place.
struct ServoLog {
  double *q;            // (capacity + 1, nq): q[0] is q0
  double *rates;        // (capacity, nv)
  double *position;     // (capacity + 1,)
  double *orientation;  // (capacity + 1,)
  double *radius;       // (capacity + 1,)
  int *flags;           // (capacity,)
  double *scale;        // (capacity,)
  int *hit;             // (capacity,): the first limit clamped, -1 for none
  long capacity;
};

class Servo {
 public:
  Servo(Kinematics &kinematics, Settings settings) : kin_(kinematics), s_(std::move(settings)) {
    n_ = static_cast<int>(s_.columns.size());
    k_ = static_cast<int>(s_.rows.size()) - s_.m;
    displacement_ = Vector::Zero(kin_.nv());
  }

  // Blocks A, B, U, W of the sensor-frame J (closed_form.blocks).
  Blocks blocks() const {
    const auto &J = kin_.jacobian;
    Blocks b;
    auto fill = [&](Block &M, int row0, int rows, int col0, int cols) {
      M.rows = rows;
      M.cols = cols;
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) M(r, c) = J(s_.rows[row0 + r], s_.columns[col0 + c]);
    };
    fill(b.A, 0, s_.m, 0, s_.n_arm);
    fill(b.B, 0, s_.m, s_.n_arm, n_ - s_.n_arm);
    fill(b.U, s_.m, k_, 0, s_.n_arm);
    fill(b.W, s_.m, k_, s_.n_arm, n_ - s_.n_arm);
    return b;
  }

  // rho of the smaller of G and H; inf where A or W is singular.
  static double radius_of(const Blocks &b) {
    try {
      return spectral_radius(b.A, b.B, b.U, b.W);
    } catch (const Singular &) {
      return INFINITY;
    }
  }

  // The loop from state.step_number; returns an Outcome.
  int run(Eigen::Ref<const Vector> q0, const SE3 &target, double gain, double tol, long stall_steps, long max_steps,
          double divergence_factor, double stall_improvement, ServoState &state, ServoLog &log,
          const std::function<bool()> &interrupted, Collision *collision = nullptr) {
    const int nq = kin_.nq(), nv = kin_.nv();
    // The step's vectors live across steps: the loop allocates nothing per step.
    Vector q = q0, next(nq), rates(nv);
    const long first = state.step_number;
    for (;; ++state.step_number) {
      const long step = state.step_number;
      if (step > log.capacity) return FULL;
      if (step > first && (step - first) % kSignalCheckSteps == 0 && interrupted()) return INTERRUPTED;
      kin_.compute(q);
      const Eigen::Matrix<double, 6, 1> full_error = kin_.pose_error(target);
      double error[6];
      for (int r = 0; r < s_.m + k_; ++r) error[r] = full_error[s_.rows[r]];
      const double position = std::sqrt(dot(error, error, s_.m));
      const double orientation = std::sqrt(dot(error + s_.m, error + s_.m, k_));
      const Blocks parts = s_.small ? blocks() : Blocks{};
      const bool need_reduced = !s_.small || s_.measure_j;
      Matrix R = need_reduced ? reduced() : Matrix();
      log.position[step] = position;
      log.orientation[step] = orientation;
      log.radius[step] = s_.small ? radius_of(parts) : general_radius(R);
      const double total = position + orientation;
      if (position < tol && orientation < tol) return CONVERGED;
      state.best = py_min(state.best, total);
      if (total > divergence_factor * state.best + tol) return DIVERGING;
      if (total < (1.0 - stall_improvement) * state.progress) {
        state.progress = total;
        state.progress_step = step;
      } else if (step - state.progress_step >= stall_steps) {
        return STALLED;
      }
      if (step == max_steps) return MAX_STEPS;
      if (step == log.capacity) return FULL;  // no row for the next q
      double twist[6];
      for (int r = 0; r < s_.m + k_; ++r) twist[r] = gain * error[r];
      Taken taken;
      // A step the collision monitor slows or halts is Python's (the log has no room for
      // its words): the loop hands it back.
      if (!advance(q, twist, parts, R, rates, next, taken, collision, true)) return HANDBACK;
      log.flags[step] = taken.flags;
      log.scale[step] = taken.scale;
      log.hit[step] = taken.hit;
      std::copy(rates.data(), rates.data() + nv, log.rates + step * nv);
      std::copy(next.data(), next.data() + nq, log.q + (step + 1) * nq);
      q.swap(next);
    }
  }

  // One step's common path (Controller.step's), from the J of kin_ at q and the commanded
  // twist (partition order, sensor axes; saturated in place): saturation, the conditioning
  // bound, the algorithm, the position-limit test, the decelerate look-ahead, the velocity
  // scale, the collision monitor (when given), integration and the clamp. parts and R are J's
  // blocks and reduced J where the caller has them (R may be empty: made here when needed).
  // false: the step is Python's (with hand_back_collision, any step the monitor slows or halts).
  bool advance(const Vector &q, double *twist, const Blocks &parts, Matrix &R, Vector &rates, Vector &next,
               Taken &taken, Collision *collision = nullptr, bool hand_back_collision = false) {
    const bool need_reduced = !s_.small || s_.measure_j;
    int flags = 0;
    if (saturate(twist)) flags |= SATURATED;
    const double bound = conditioning_bound(parts, R);
    // Under the cheap bound, the SVDs decide (Controller._plan): in the singular region a
    // plan, which Python makes; above it after all, the algorithm as it is.
    if (bound < s_.slow_threshold) {
      if (!need_reduced) R = reduced();
      if (conditioning(R) < s_.slow_threshold) return false;
    }
    rates.setZero();
    if (!(s_.small ? solve(parts, twist, rates) : solve_general(R, twist, rates))) return false;
    if (s_.position_limits && passing(q, rates)) return false;
    if (s_.watch && !(bound >= s_.watch_factor * s_.slow_threshold || max_abs(rates) * s_.dt <= s_.watched_step))
      return false;  // decelerate judges this step one step ahead
    const double scale = rate_scale(rates);
    if (scale < 1.0) {
      rates *= scale;
      flags |= RATE_LIMITED_FLAG;
    }
    if (collision != nullptr) {  // Finish: after the velocity scale, before integration
      const CollisionVerdict &verdict = collision->limit(q, rates, s_.dt);
      if (verdict.kind != COLLISION_CLEAR && hand_back_collision) return false;
      if (verdict.kind == COLLISION_HALTED) {  // Finish.halt: q kept, rates 0, no other condition
        rates.setZero();
        next = q;
        taken = {COLLISION_HALTED_FLAG, scale, -1};
        return true;
      }
      if (verdict.kind == COLLISION_SLOWED) {
        rates *= verdict.scale;
        flags |= COLLISION_SLOWED_FLAG;
      }
    }
    displacement_ = rates * s_.dt;
    pinocchio::integrate(kin_.model, q, displacement_, next);
    int hit = -1;
    if (s_.position_limits) hit = clamp(next, q, rates);
    if (hit >= 0) flags |= CLAMPED;
    taken = {flags, scale, hit};
    return true;
  }

  // Robot.check_q and Controller.check_inside_limits at q (nq,): every entry finite and
  // within the physical bound, each continuous joint's (cos, sin) pair of unit norm (the same
  // Pinocchio test on the same joints), q inside the limits the controller keeps. false:
  // Python's checks say what is wrong.
  bool admits(const Vector &q) const {
    for (int i = 0; i < q.size(); ++i)
      if (!(std::fabs(q[i]) <= kPhysicalBound)) return false;
    return pinocchio::isNormalized(kin_.model, q, kUnitTolerance) && inside(q);
  }

  // Controller.check_inside_limits: q (nq,) inside every limit the controller keeps.
  bool inside(const Vector &q) const {
    if (!s_.position_limits) return true;
    for (const Limit &limit : s_.limits) {
      const double value = q[limit.q_index];
      if (!(limit.lower <= value && value <= limit.upper)) return false;
    }
    return true;
  }

  // checks.check_vector's test of a twist (m + k,): every entry finite and within the bound.
  bool admits_twist(const double *twist) const {
    for (int i = 0; i < s_.m + k_; ++i)
      if (!(std::fabs(twist[i]) <= kPhysicalBound)) return false;
    return true;
  }

  // Controller.step per call at an admitted q (nq,): the kinematics pass (kin_ then holds J
  // and the poses at q), the twist -- the command's (m + k,; partition order, sensor axes),
  // or, with a target, gain times the pose error to it, written into twist -- then advance;
  // rates() and next() hold the step. false: the step is Python's.
  bool step_at(const Vector &q, const SE3 *target, double gain, double *twist, Taken &taken,
               Collision *collision = nullptr) {
    kin_.compute(q);
    if (target != nullptr) {
      const Eigen::Matrix<double, 6, 1> error = kin_.pose_error(*target);
      for (int r = 0; r < s_.m + k_; ++r) twist[r] = gain * error[s_.rows[r]];
    }
    return step_from_jacobian(q, twist, taken, collision);
  }

  // Controller.step per call at q (nq,) with kin_.jacobian already J at q (the caller's
  // kinematics pass): the blocks from it, then advance.
  bool step_from_jacobian(const Vector &q, double *twist, Taken &taken, Collision *collision = nullptr) {
    const Blocks parts = s_.small ? blocks() : Blocks{};
    Matrix R = !s_.small || s_.measure_j ? reduced() : Matrix();
    return advance(q, twist, parts, R, rates_, next_, taken, collision);
  }

  // The per-call step's vectors: q (nq,) as the caller fills it, and the step's rates (nv,)
  // and next q (nq,).
  Vector &working_q() {
    if (q_.size() != kin_.nq()) q_.resize(kin_.nq()), next_.resize(kin_.nq()), rates_.resize(kin_.nv());
    return q_;
  }
  const Vector &rates() const { return rates_; }
  const Vector &next() const { return next_; }

  int n() const { return n_; }

  // rho at the configuration of the last kinematics pass.
  double radius_here() const { return s_.small ? radius_of(blocks()) : general_radius(reduced()); }
  Kinematics &kinematics() const { return kin_; }
  const Settings &settings() const { return s_; }

 private:
  Kinematics &kin_;
  Settings s_;
  int n_ = 0, k_ = 0;
  Vector displacement_;       // rates * dt, kept across steps: a step allocates no vector of nv
  Vector q_, rates_, next_;  // the per-call step's vectors, sized on its first call (working_q)

  // spatial.saturate_twist: the whole twist scaled by one factor, the largest that meets both
  // speed limits, so the commanded screw keeps its direction (the same operations as Python).
  bool saturate(double *twist) const {
    double factor = 1.0;
    const double linear = std::sqrt(dot(twist, twist, s_.m));
    const double angular = std::sqrt(dot(twist + s_.m, twist + s_.m, k_));
    if (linear > s_.max_linear_speed) factor = s_.max_linear_speed / linear;
    if (angular > s_.max_angular_speed) factor = std::fmin(factor, s_.max_angular_speed / angular);
    if (!(factor < 1.0)) return false;
    for (int i = 0; i < s_.m + k_; ++i) twist[i] = twist[i] * factor;
    return true;
  }

  static double max_abs(const Vector &rates) {
    double largest = 0.0;
    for (int i = 0; i < rates.size(); ++i) largest = std::fmax(largest, std::fabs(rates[i]));
    return largest;
  }

  Eigen::MatrixXd reduced() const {
    Eigen::MatrixXd R(s_.m + k_, n_);
    for (int r = 0; r < s_.m + k_; ++r)
      for (int c = 0; c < n_; ++c) R(r, c) = kin_.jacobian(s_.rows[r], s_.columns[c]);
    return R;
  }

  // Controller._conditioning_bound: the least 1 / (||M||_F ||M^-1||_F) of the measured blocks.
  double conditioning_bound(const Blocks &b, const Matrix &R) const {
    double bound = INFINITY;
    if (s_.measure_j) {
      if (R.rows() != R.cols()) return 0.0;
      Square scaled = R;  // at most 6 x 6: on the stack
      for (int r = 0; r < scaled.rows(); ++r) scaled.row(r) *= s_.row_scale[r];
      Eigen::PartialPivLU<Square> lu(scaled);
      const Square inverse = lu.inverse();
      const double matrix_norm2 = scaled.squaredNorm(), inverse_norm2 = inverse.squaredNorm();
      const double product = matrix_norm2 * inverse_norm2;
      if (!(product > 0.0) || !std::isfinite(product)) return 0.0;
      bound = py_min(bound, 1.0 / std::sqrt(product));
    }
    if (!s_.small && (s_.measure_a || s_.measure_w)) return 0.0;  // no closed-form inverse to bound with
    try {
      if (s_.measure_a && b.A.rows && b.A.cols) bound = py_min(bound, inverse_condition_bound(b.A, inverse(b.A, "A")));
      if (s_.measure_w && b.W.rows && b.W.cols) bound = py_min(bound, inverse_condition_bound(b.W, inverse(b.W, "W")));
    } catch (const Singular &) {
      return 0.0;
    }
    return bound;
  }

  // solvers.rates.partition_rates; false where Python must take the step (a singular block,
  // an exact step that needs the least-squares solution).
  bool solve(const Blocks &b, const double *twist, Vector &rates) const {
    if (s_.kernel == EXACT || s_.kernel == DLS) {
      const Eigen::MatrixXd J = reduced();
      Eigen::VectorXd command(s_.m + k_);
      for (int r = 0; r < s_.m + k_; ++r) command[r] = twist[r];
      Eigen::VectorXd solved;
      if (s_.kernel == EXACT) {
        // reference.exact: one solve where J is square, unless the solution is so large that
        // it betrays a singular J; else (and for a J not square) the least-squares J^+ s.
        bool solved_square = false;
        if (J.rows() == J.cols() && J.rows() > 0) {
          solved = Square(J).partialPivLu().solve(command);  // at most 6 x 6: on the stack
          const double growth = J.squaredNorm() * solved.squaredNorm() * (s_.exact_rcond * s_.exact_rcond);
          solved_square = growth <= command.squaredNorm();
        }
        if (!solved_square) solved = J.size() ? Eigen::VectorXd(pinv(J, s_.pinv_rcond) * command) : Eigen::VectorXd::Zero(n_);
      } else {
        Eigen::MatrixXd normal = J * J.transpose();
        normal.diagonal().array() += s_.dls_damping * s_.dls_damping;
        solved = J.transpose() * normal.partialPivLu().solve(command);
      }
      for (int c = 0; c < n_; ++c) rates[s_.columns[c]] = solved[c];
      return true;
    }
    Vec3 v, omega;
    v.n = s_.m;
    omega.n = k_;
    for (int r = 0; r < s_.m; ++r) v[r] = twist[r];
    for (int r = 0; r < k_; ++r) omega[r] = twist[s_.m + r];
    Rates solved;
    try {
      switch (s_.kernel) {
        case SCHUR: solved = schur(b.A, b.B, b.U, b.W, v, omega); break;
        case MCA1: solved = mca1(b.A, b.B, b.U, b.W, v, omega); break;
        case MCA2: solved = mca2(b.A, b.B, b.U, b.W, v, omega); break;
        default: solved = mca3(b.A, b.B, b.U, b.W, v, omega); break;
      }
    } catch (const Singular &) {
      return false;
    }
    for (int c = 0; c < s_.n_arm; ++c) rates[s_.columns[c]] = solved.arm[c];
    for (int c = s_.n_arm; c < n_; ++c) rates[s_.columns[c]] = solved.wrist[c - s_.n_arm];
    return true;
  }

  // singularity.conditioning: the least sigma_r / sigma_1 of the measured blocks (J's rows
  // scaled), r capped at each block's generic rank; 1 when none is measured.
  double conditioning(const Matrix &R) const {
    double worst = 1.0;
    const int n_wrist = n_ - s_.n_arm;
    auto consider = [&](const Matrix &M, int cap) {
      if (M.size() == 0) return;
      const int rank = std::min(static_cast<int>(std::min(M.rows(), M.cols())), cap);
      if (rank == 0) return;
      worst = std::fmin(worst, inverse_condition(M, rank));
    };
    if (s_.measure_a) consider(R.topLeftCorner(s_.m, s_.n_arm), s_.rank_a);
    if (s_.measure_w) consider(R.bottomRightCorner(k_, n_wrist), s_.rank_w);
    if (s_.measure_j) {
      Matrix scaled = R;
      for (int r = 0; r < scaled.rows(); ++r) scaled.row(r) *= s_.row_scale[r];
      consider(scaled, s_.rank_j);
    }
    return worst;
  }

  double general_radius(const Matrix &R) const {
    const int n_wrist = n_ - s_.n_arm;
    return general_spectral_radius(R.topLeftCorner(s_.m, s_.n_arm), R.topRightCorner(s_.m, n_wrist),
                                   R.bottomLeftCorner(k_, s_.n_arm), R.bottomRightCorner(k_, n_wrist), s_.pinv_rcond);
  }

  // solvers.rates.partition_rates for blocks of any shape (reference kernels).
  bool solve_general(const Matrix &R, const double *twist, Vector &rates) const {
    if (s_.kernel == EXACT || s_.kernel == DLS) {
      Blocks none;
      return solve(none, twist, rates);
    }
    const int n_wrist = n_ - s_.n_arm;
    Eigen::VectorXd v(s_.m), omega(k_);
    for (int r = 0; r < s_.m; ++r) v[r] = twist[r];
    for (int r = 0; r < k_; ++r) omega[r] = twist[s_.m + r];
    GeneralRates solved;
    try {
      solved = general_kernel(s_.kernel, R.topLeftCorner(s_.m, s_.n_arm), R.topRightCorner(s_.m, n_wrist),
                              R.bottomLeftCorner(k_, s_.n_arm), R.bottomRightCorner(k_, n_wrist), v, omega,
                              s_.pinv_rcond);
    } catch (const Singular &) {
      return false;
    }
    for (int c = 0; c < s_.n_arm; ++c) rates[s_.columns[c]] = solved.arm[c];
    for (int c = s_.n_arm; c < n_; ++c) rates[s_.columns[c]] = solved.wrist[c - s_.n_arm];
    return true;
  }

  // Controller._passing: some joint's commanded rate carries it past a limit within dt.
  bool passing(const Vector &q, const Vector &rates) const {
    for (const Limit &limit : s_.limits) {
      const double rate = rates[limit.v_index];
      const double value = q[limit.q_index] + rate * s_.dt;
      if ((value > limit.upper && rate > 0.0) || (value < limit.lower && rate < 0.0)) return true;
    }
    return false;
  }

  // Controller._rate_scale: the largest factor <= 1 meeting every velocity limit.
  double rate_scale(const Vector &rates) const {
    double scale = 1.0;
    for (const RateLimit &row : s_.rate_limits) {
      const double magnitude = std::fabs(rates[row.v_index]);
      if (magnitude * scale > row.limit) scale = row.limit / magnitude;
    }
    return scale;
  }

  // PositionLimits.clamp: next clamped to the limits, a clamped joint's rate set to the one
  // that reaches its bound from q in dt (the rates logged are the rates applied); the first
  // limit it was past, or -1.
  int clamp(Vector &next, const Vector &q, Vector &rates) const {
    int hit = -1;
    for (std::size_t i = 0; i < s_.limits.size(); ++i) {
      const Limit &limit = s_.limits[i];
      const double value = next[limit.q_index];
      if (value < limit.lower || value > limit.upper) {
        const double bound = value < limit.lower ? limit.lower : limit.upper;
        next[limit.q_index] = bound;
        rates[limit.v_index] = (bound - q[limit.q_index]) / s_.dt;
        if (hit < 0) hit = static_cast<int>(i);
      }
    }
    return hit;
  }
};

}  // namespace pinrate_core
