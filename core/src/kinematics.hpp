// A private Pinocchio model rebuilt from the Python model's arrays, and pinrate's one
// kinematics pass (pinrate.kinematics.manipulator.Robot.kinematics) on it.
//
// Header-only Pinocchio: nothing links libpinocchio_default.so, so the module does not care
// which pin release the Python side runs. The same joints in the same order with the same
// placements make the same Pinocchio calls as the Python side, so J and the poses agree
// with pin's to the last bit where both builds round alike.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "pinocchio/algorithm/frames.hpp"
#include "pinocchio/algorithm/jacobian.hpp"
#include "pinocchio/algorithm/joint-configuration.hpp"
#include "pinocchio/multibody.hpp"
#include "pinocchio/spatial.hpp"

namespace pinrate_core {

using Model = pinocchio::Model;
using Data = pinocchio::Data;
using SE3 = pinocchio::SE3;
using Matrix6x = Eigen::Matrix<double, 6, Eigen::Dynamic>;
using Vector = Eigen::VectorXd;

// The joint kinds rebuilt here (pin's JointModel shortname()), exported as
// pinrate_core.JOINT_KINDS and checked against pinrate.compiled.boundary.REBUILT_JOINTS; a
// robot with any other runs on the Python side's own path.
struct JointKind {
  const char *name;
  pinocchio::JointModel (*make)(const Eigen::Vector3d &axis);
};

inline const std::array<JointKind, 12> &joint_kinds() {
  using namespace pinocchio;
  using Axis = const Eigen::Vector3d &;
  static const std::array<JointKind, 12> kinds = {{
      {"JointModelRX", [](Axis) -> JointModel { return JointModelRX(); }},
      {"JointModelRY", [](Axis) -> JointModel { return JointModelRY(); }},
      {"JointModelRZ", [](Axis) -> JointModel { return JointModelRZ(); }},
      {"JointModelRevoluteUnaligned", [](Axis axis) -> JointModel { return JointModelRevoluteUnaligned(axis); }},
      {"JointModelRUBX", [](Axis) -> JointModel { return JointModelRUBX(); }},
      {"JointModelRUBY", [](Axis) -> JointModel { return JointModelRUBY(); }},
      {"JointModelRUBZ", [](Axis) -> JointModel { return JointModelRUBZ(); }},
      {"JointModelRevoluteUnboundedUnaligned",
       [](Axis axis) -> JointModel { return JointModelRevoluteUnboundedUnaligned(axis); }},
      {"JointModelPX", [](Axis) -> JointModel { return JointModelPX(); }},
      {"JointModelPY", [](Axis) -> JointModel { return JointModelPY(); }},
      {"JointModelPZ", [](Axis) -> JointModel { return JointModelPZ(); }},
      {"JointModelPrismaticUnaligned", [](Axis axis) -> JointModel { return JointModelPrismaticUnaligned(axis); }},
  }};
  return kinds;
}

inline pinocchio::JointModel joint_model(const std::string &kind, const Eigen::Vector3d &axis) {
  for (const JointKind &known : joint_kinds())
    if (kind == known.name) return known.make(axis);
  throw std::invalid_argument("joint kind " + kind + " is not supported by the compiled core");
}

inline SE3 se3_from(const double *homogeneous) {  // a row-major 4x4
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation(r, c) = homogeneous[4 * r + c];
    translation[r] = homogeneous[4 * r + 3];
  }
  return SE3(rotation, translation);
}

// The arm's kinematics: J in the sensor frame's axes (6, nv), the tip and sensor poses.
struct Kinematics {
  Model model;
  Data data;
  pinocchio::FrameIndex tip = 0, sensor = 0;
  bool sensor_is_tip = true;
  Matrix6x jacobian_local, jacobian;
  SE3 world_T_tip, world_T_sensor;

  Kinematics(const Kinematics &other, int)
      : model(other.model),
        data(other.model),
        tip(other.tip),
        sensor(other.sensor),
        sensor_is_tip(other.sensor_is_tip),
        jacobian_local(Matrix6x::Zero(6, other.model.nv)),
        jacobian(Matrix6x::Zero(6, other.model.nv)) {}

  Kinematics(const std::vector<std::string> &kinds, const std::vector<int> &parents, const double *axes,
             const double *placements, int tip_joint, const double *tip_placement, int sensor_joint,
             const double *sensor_placement, bool same_frame) {
    for (std::size_t i = 0; i < kinds.size(); ++i) {
      const Eigen::Vector3d axis(axes[3 * i], axes[3 * i + 1], axes[3 * i + 2]);
      model.addJoint(static_cast<pinocchio::JointIndex>(parents[i]), joint_model(kinds[i], axis),
                     se3_from(placements + 16 * i), "joint_" + std::to_string(i + 1));
    }
    tip = model.addFrame(pinocchio::Frame("tip", static_cast<pinocchio::JointIndex>(tip_joint), 0,
                                          se3_from(tip_placement), pinocchio::OP_FRAME));
    sensor_is_tip = same_frame;
    sensor = same_frame ? tip
                        : model.addFrame(pinocchio::Frame("sensor", static_cast<pinocchio::JointIndex>(sensor_joint), 0,
                                                          se3_from(sensor_placement), pinocchio::OP_FRAME));
    data = Data(model);
    jacobian_local = Matrix6x::Zero(6, model.nv);
    jacobian = Matrix6x::Zero(6, model.nv);
  }

  // A twin with its own Data and buffers (the model, read-only, copied): a loop that releases
  // the GIL works on its own, whatever another thread does with this one.
  Kinematics fresh() const {
    Kinematics twin(*this, 0);
    return twin;
  }

  int nq() const { return model.nq; }
  int nv() const { return model.nv; }

  // Robot.kinematics: computeJointJacobians, the tip's LOCAL Jacobian, the frame placements;
  // with the sensor elsewhere J is turned into the sensor's axes by sensor_R_tip.
  void compute(Eigen::Ref<const Vector> q) {
    pinocchio::computeJointJacobians(model, data, q);
    jacobian_local.setZero();
    pinocchio::getFrameJacobian(model, data, tip, pinocchio::LOCAL, jacobian_local);
    world_T_tip = pinocchio::updateFramePlacement(model, data, tip);
    if (sensor_is_tip) {
      world_T_sensor = world_T_tip;
      jacobian = jacobian_local;
      return;
    }
    world_T_sensor = pinocchio::updateFramePlacement(model, data, sensor);
    const Eigen::Matrix3d sensor_R_tip = world_T_sensor.rotation().transpose() * world_T_tip.rotation();
    jacobian.topRows<3>().noalias() = sensor_R_tip * jacobian_local.topRows<3>();
    jacobian.bottomRows<3>().noalias() = sensor_R_tip * jacobian_local.bottomRows<3>();
  }

  // Only J (sampling the work volume): with the sensor at the tip, computeFrameJacobian.
  void compute_jacobian(Eigen::Ref<const Vector> q) {
    if (!sensor_is_tip) {
      compute(q);
      return;
    }
    jacobian.setZero();
    pinocchio::computeFrameJacobian(model, data, q, tip, pinocchio::LOCAL, jacobian);
  }

  // pinrate.kinematics.spatial.pose_error: [R_s^T (p_target - p_tip); R_s^T log3(R_target R_tip^T)].
  Eigen::Matrix<double, 6, 1> pose_error(const SE3 &target) const {
    Eigen::Matrix<double, 6, 1> error;
    // Exactly zero at the target: log3 of R^T R (the identity to rounding) is about 1e-16 rad.
    if (world_T_tip.rotation() == target.rotation() && world_T_tip.translation() == target.translation()) {
      error.setZero();
      return error;
    }
    const SE3 sensor_T_target = world_T_sensor.actInv(target);
    if (sensor_is_tip) {
      error.head<3>() = sensor_T_target.translation();
      error.tail<3>() = pinocchio::log3(sensor_T_target.rotation());
      return error;
    }
    const SE3 sensor_T_tip = world_T_sensor.actInv(world_T_tip);
    error.head<3>() = sensor_T_target.translation() - sensor_T_tip.translation();
    const Eigen::Matrix3d relative = sensor_T_target.rotation() * sensor_T_tip.rotation().transpose();
    error.tail<3>() = pinocchio::log3(relative);
    return error;
  }

  Vector integrate(const Vector &q, const Vector &displacement) const {
    Vector next(model.nq);
    pinocchio::integrate(model, q, displacement, next);
    return next;
  }
};

}  // namespace pinrate_core
