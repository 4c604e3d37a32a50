// Poses and joint states the robot_client tests share.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "robot_client/ur/pose.h"

namespace cornerpose::robot_client::testing {

// The UR controller emulator's start-up joints (UrEmulatorOptions'
// initial_joints): the flange above the table, tool pointing down.
inline constexpr ur::Joints kEmulatorHomeJoints = {0.0, -1.571, 1.571, -1.571, -1.571, 0.0};

// A TCP pose at (x, y, z) in the base frame with the tool pointing down
// (tool z = base -z), turned by `yaw` about base z.
inline Eigen::Isometry3d ToolDownAt(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

}  // namespace cornerpose::robot_client::testing
