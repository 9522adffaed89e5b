// pinrate.control.collision's monitor (CollisionMonitor.limit) on coal, for the compiled step.
//
// Python decides what is monitored and hands it here once (pinrate.control.core_collision):
// each geometry's parent joint, its placement in that joint's frame and its shape (a mesh
// Python hulled, hulled again here by the same coal call on the same vertices; a mesh kept as
// it is; a box, sphere, cylinder or capsule), the monitored pairs, and the rules (the
// monitor's distances, the damper's approach speed, the halt scale, the distance request's
// settings). Per step the same Pinocchio and coal calls on the same numbers as the Python
// monitor: geometry placements from the forward kinematics (updateGeometryPlacements),
// coal's ComputeDistance per pair with the monitor's DistanceRequest, the velocity damper, the check
// at the integrated q. The verdict's words are Python's (the core hands back the pair, its
// distance and the scale).
#pragma once

#include <coal/BVH/BVH_model.h>
#include <coal/collision_data.h>
#include <coal/distance.h>
#include <coal/shape/geometric_shapes.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "kinematics.hpp"
#include "pinocchio/algorithm/jacobian.hpp"
#include "pinocchio/algorithm/joint-configuration.hpp"
#include "pinocchio/algorithm/kinematics.hpp"

namespace pinrate_core {

// The monitor's rules, each read from pinrate.control.collision (never typed here).
// GJK's initial guess by its coal name (the Python monitor passes request.gjk_initial_guess.name).
inline coal::GJKInitialGuess gjk_guess_of(const std::string &name) {
  if (name == "DefaultGuess") return coal::GJKInitialGuess::DefaultGuess;
  if (name == "CachedGuess") return coal::GJKInitialGuess::CachedGuess;
  if (name == "BoundingVolumeGuess") return coal::GJKInitialGuess::BoundingVolumeGuess;
  throw std::invalid_argument("coal has no GJK initial guess " + name);
}

struct CollisionRules {
  double safety_distance{}, stop_distance{};  // m: the monitor's
  double approach_speed{};                    // m/s: APPROACH_SPEED
  double halt_scale{};                        // HALT_SCALE
  double coincident{};                        // m: COINCIDENT, nearest points this close give no normal
  double gjk_tolerance{};                     // the Python monitor's DistanceRequests'
  bool cached_gjk_guess{};                    // likewise (false: no warm start from the last result)
};

// One geometry as Python describes it: kind "hull" (vertices, hulled here), "mesh"
// (vertices and triangles), "box" (half sides), "sphere" (radius), "cylinder" and "capsule"
// (radius, half length), or "unused" (in no pair).
inline std::shared_ptr<coal::CollisionGeometry> make_geometry(const std::string &kind,
                                                              const std::vector<double> &numbers,
                                                              const std::vector<long> &triangles) {
  const auto need = [&](std::size_t count) {
    if (numbers.size() != count) throw std::invalid_argument("a " + kind + " takes " + std::to_string(count) + " numbers");
  };
  if (kind == "unused") return nullptr;
  // Every geometry's local bounding box computed, as the Python monitor computes them (GJK's
  // BoundingVolumeGuess starts from their centres).
  const auto bounded = [](std::shared_ptr<coal::CollisionGeometry> geometry) {
    geometry->computeLocalAABB();
    return geometry;
  };
  if (kind == "box") {
    need(3);  // half sides: Box(2 h) stores 2 h / 2 = h exactly
    return bounded(std::make_shared<coal::Box>(2.0 * numbers[0], 2.0 * numbers[1], 2.0 * numbers[2]));
  }
  if (kind == "sphere") {
    need(1);
    return bounded(std::make_shared<coal::Sphere>(numbers[0]));
  }
  if (kind == "cylinder") {
    need(2);
    return bounded(std::make_shared<coal::Cylinder>(numbers[0], 2.0 * numbers[1]));
  }
  if (kind == "capsule") {
    need(2);
    return bounded(std::make_shared<coal::Capsule>(numbers[0], 2.0 * numbers[1]));
  }
  if (kind != "hull" && kind != "mesh") throw std::invalid_argument("the compiled core has no geometry kind " + kind);
  if (numbers.size() % 3 != 0 || numbers.empty()) throw std::invalid_argument("vertices must be (V, 3)");
  auto vertices = std::make_shared<std::vector<coal::Vec3s>>();
  for (std::size_t i = 0; i < numbers.size(); i += 3) vertices->emplace_back(numbers[i], numbers[i + 1], numbers[i + 2]);
  if (kind == "hull") {
    // collision.py's _to_convex_hull: BVHModelBase.buildConvexHull(False, "") on the mesh's
    // vertices, which is this call (qhull's command "" as the Python binding passes it).
    std::shared_ptr<coal::CollisionGeometry> hull(
        coal::ConvexBase::convexHull(vertices, static_cast<unsigned int>(vertices->size()), false, ""));
    return bounded(hull);
  }
  if (triangles.size() % 3 != 0) throw std::invalid_argument("triangles must be (T, 3)");
  std::vector<coal::Triangle> faces;
  for (std::size_t i = 0; i < triangles.size(); i += 3) {
    for (std::size_t k = 0; k < 3; ++k)
      if (triangles[i + k] < 0 || static_cast<std::size_t>(triangles[i + k]) >= vertices->size())
        throw std::invalid_argument("a triangle names no vertex");
    faces.emplace_back(static_cast<coal::Triangle::index_type>(triangles[i]),
                       static_cast<coal::Triangle::index_type>(triangles[i + 1]),
                       static_cast<coal::Triangle::index_type>(triangles[i + 2]));
  }
  auto mesh = std::make_shared<coal::BVHModel<coal::OBBRSS>>();  // pin's URDF meshes are OBBRSS
  mesh->beginModel(static_cast<unsigned int>(faces.size()), static_cast<unsigned int>(vertices->size()));
  mesh->addSubModel(*vertices, faces);
  mesh->endModel();
  return bounded(mesh);
}

// What the monitor makes of a step: kind (CLEAR, SLOWED or HALTED), the factor of every rate,
// the limiting pair (its index in the pair list, -1 for none) and its distance at q (m).
enum CollisionKind { COLLISION_CLEAR = 0, COLLISION_SLOWED = 1, COLLISION_HALTED = 2 };
struct CollisionVerdict {
  int kind = COLLISION_CLEAR;
  double scale = 1.0;
  int pair = -1;
  double distance = 0.0;
};

class Collision {
 public:
  Collision(const Kinematics &kinematics, std::vector<std::shared_ptr<coal::CollisionGeometry>> geometries,
            std::vector<int> joints, std::vector<SE3> placements, const std::vector<int> &firsts,
            const std::vector<int> &seconds, const std::vector<coal::GJKInitialGuess> &guesses,
            const CollisionRules &rules)
      : model_(kinematics.model),
        data_(model_),
        ahead_(model_),
        geometries_(std::move(geometries)),
        joints_(std::move(joints)),
        placements_(std::move(placements)),
        rules_(rules) {
    const std::size_t count = geometries_.size();
    if (joints_.size() != count || placements_.size() != count || firsts.size() != seconds.size() ||
        guesses.size() != firsts.size())
      throw std::invalid_argument("collision arrays of mismatched sizes");
    for (int joint : joints_)
      if (joint < 0 || joint >= model_.njoints) throw std::invalid_argument("a geometry's joint is not in the model");
    for (std::size_t i = 0; i < firsts.size(); ++i) {
      const int a = firsts[i], b = seconds[i];
      if (a < 0 || b < 0 || static_cast<std::size_t>(a) >= count || static_cast<std::size_t>(b) >= count ||
          !geometries_[a] || !geometries_[b])
        throw std::invalid_argument("a pair names no geometry");
      pairs_.push_back({a, b});
      functors_.emplace_back(geometries_[a].get(), geometries_[b].get());
      // pin's GeometryData: DistanceRequest(true) per pair, then the Python monitor's
      // settings (GJK started from the bounding boxes' centres, or coal's default guess
      // beside a mesh, never from the pair's last result: each distance a function of q).
      requests_.emplace_back(true);
      requests_.back().gjk_tolerance = rules_.gjk_tolerance;
      requests_.back().enable_cached_gjk_guess = rules_.cached_gjk_guess;
      requests_.back().gjk_initial_guess = guesses[i];
    }
    results_.resize(pairs_.size());
    distances_.resize(pairs_.size());
    placed_.resize(count);
    jacobian_ = Matrix6x::Zero(6, model_.nv);
    next_ = Vector::Zero(model_.nq);
    displacement_ = Vector::Zero(model_.nv);
  }

  std::size_t pair_count() const { return pairs_.size(); }
  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }
  const CollisionVerdict &last() const { return last_; }

  // CollisionMonitor.limit: the verdict on a step of rates (nv,) over dt (s) from q (nq,).
  const CollisionVerdict &limit(const Vector &q, const Vector &rates, double dt) {
    last_ = CollisionVerdict{};
    pinocchio::computeJointJacobians(model_, data_, q);  // oMi for the distances, J for the rates
    place(data_);
    near_.clear();
    for (std::size_t i = 0; i < pairs_.size(); ++i) {
      distances_[i] = distance(i, results_[i]);
      if (distances_[i] < rules_.safety_distance) near_.push_back(i);
    }
    if (near_.empty()) return last_;
    const double span = rules_.safety_distance - rules_.stop_distance;
    double scale = 1.0;
    long limiting = -1;
    for (std::size_t i : near_) {
      const double rate = approach_rate(i, rates);
      if (rate >= 0.0) continue;  // separating: never limited
      const double room = distances_[i] - rules_.stop_distance;
      const double allowed = py_min(rules_.approach_speed * room / (span * -rate), room / (-rate * dt));
      if (allowed < scale) {
        scale = 0.0 > allowed ? 0.0 : allowed;  // Python's max(allowed, 0.0)
        limiting = static_cast<long>(i);
      }
    }
    if (scale > 0.0) {
      // Robot.integrate(q, rates * scale, dt): pin.integrate(q, (rates * scale) * dt).
      displacement_ = (rates * scale) * dt;
      pinocchio::integrate(model_, q, displacement_, next_);
      pinocchio::forwardKinematics(model_, ahead_, next_);
      place(ahead_);
      coal::DistanceResult after_result;
      long closing = -1;
      for (std::size_t i : near_) {  // every near pair, as Python asks them
        const double after = distance(i, after_result);
        if (closing < 0 && after < rules_.stop_distance && after < distances_[i]) closing = static_cast<long>(i);
      }
      if (closing >= 0) {
        scale = 0.0;
        limiting = closing;
      }
    }
    if (limiting < 0) return last_;
    last_.pair = static_cast<int>(limiting);
    last_.distance = distances_[limiting];
    if (scale < rules_.halt_scale) {
      last_.kind = COLLISION_HALTED;
      last_.scale = 0.0;
    } else {
      last_.kind = COLLISION_SLOWED;
      last_.scale = scale;
    }
    return last_;
  }

  // The distance (m) of every pair at q (nq,): CollisionMonitor._distances.
  std::vector<double> distances_at(const Vector &q) {
    pinocchio::forwardKinematics(model_, ahead_, q);
    place(ahead_);
    std::vector<double> out(pairs_.size());
    coal::DistanceResult result;
    for (std::size_t i = 0; i < pairs_.size(); ++i) out[i] = distance(i, result);
    return out;
  }

 private:
  struct Pair {
    int first, second;
  };
  Model model_;  // a copy of the kinematics' (read-only there too)
  Data data_, ahead_;
  std::vector<std::shared_ptr<coal::CollisionGeometry>> geometries_;
  std::vector<int> joints_;
  std::vector<SE3> placements_;
  CollisionRules rules_;
  std::vector<coal::DistanceRequest> requests_;  // per pair, as pin's GeometryData keeps them
  std::vector<Pair> pairs_;
  std::vector<coal::ComputeDistance> functors_;
  std::vector<coal::DistanceResult> results_;  // at q, kept for the approach rates
  std::vector<double> distances_;
  std::vector<std::size_t> near_;
  std::vector<coal::Transform3s> placed_;
  Matrix6x jacobian_;
  Vector next_, displacement_;
  CollisionVerdict last_;

  static double py_min(double a, double b) { return b < a ? b : a; }  // Python's min(a, b)

  // pin.updateGeometryPlacements: oMg = oMi[joint] * placement (the placement alone on joint 0).
  void place(const Data &data) {
    for (std::size_t g = 0; g < geometries_.size(); ++g) {
      if (!geometries_[g]) continue;
      const SE3 placed = joints_[g] > 0 ? SE3(data.oMi[joints_[g]] * placements_[g]) : placements_[g];
      placed_[g] = coal::Transform3s(placed.rotation(), placed.translation());
    }
  }

  // pin.computeDistance of pair i on the placements of the last place().
  double distance(std::size_t i, coal::DistanceResult &result) {
    result.clear();
    const Pair &pair = pairs_[i];
    functors_[i](placed_[pair.first], placed_[pair.second], requests_[i], result);
    return result.min_distance;
  }

  // CollisionMonitor.approach_rates for pair i: n . (v_b(p_b) - v_a(p_a)) (m/s), n the unit
  // normal from a to b (the gradient of the signed distance), after limit()'s distances at q.
  // Operation for operation as Python makes them in floats: the same doubles.
  double approach_rate(std::size_t i, const Vector &rates) {
    const coal::DistanceResult &result = results_[i];
    const coal::Vec3s &first = result.nearest_points[0], &second = result.nearest_points[1];
    double dx = second[0] - first[0], dy = second[1] - first[1], dz = second[2] - first[2];
    const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
    double n[3];
    if (length > rules_.coincident) {
      if (result.min_distance < 0.0) dx = -dx, dy = -dy, dz = -dz;  // p_b - p_a points against n
      n[0] = dx / length, n[1] = dy / length, n[2] = dz / length;
    } else {
      n[0] = result.normal[0], n[1] = result.normal[1], n[2] = result.normal[2];
    }
    const Pair &pair = pairs_[i];
    double va[3], vb[3];
    point_velocity(joints_[pair.first], first, rates, va);
    point_velocity(joints_[pair.second], second, rates, vb);
    return n[0] * (vb[0] - va[0]) + n[1] * (vb[1] - va[1]) + n[2] * (vb[2] - va[2]);
  }

  // World velocity (m/s) of point (world, m) fixed to joint's body: the joint's
  // LOCAL_WORLD_ALIGNED twist (v, w), v + w x (p - o).
  void point_velocity(int joint, const coal::Vec3s &point, const Vector &rates, double velocity[3]) {
    if (joint == 0) {
      velocity[0] = velocity[1] = velocity[2] = 0.0;
      return;
    }
    jacobian_.setZero();
    pinocchio::getJointJacobian(model_, data_, static_cast<pinocchio::JointIndex>(joint),
                                pinocchio::LOCAL_WORLD_ALIGNED, jacobian_);
    double twist[6];
    for (int r = 0; r < 6; ++r) {
      double total = 0.0;
      for (int c = 0; c < model_.nv; ++c) total += jacobian_(r, c) * rates[c];
      twist[r] = total;
    }
    const Eigen::Vector3d &origin = data_.oMi[joint].translation();
    const double rx = point[0] - origin[0], ry = point[1] - origin[1], rz = point[2] - origin[2];
    velocity[0] = twist[0] + (twist[4] * rz - twist[5] * ry);
    velocity[1] = twist[1] + (twist[5] * rx - twist[3] * rz);
    velocity[2] = twist[2] + (twist[3] * ry - twist[4] * rx);
  }
};

}  // namespace pinrate_core
