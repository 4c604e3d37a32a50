#include "robot_client/planning/grasp_geometry.h"

#include <algorithm>
#include <cmath>

namespace cornerpose::robot_client {

Reachability MakeIkReachability(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp) {
  const Eigen::Isometry3d tcp_T_flange = flange_T_tcp.inverse();
  return [model, tcp_T_flange](const Eigen::Isometry3d& base_T_tcp) {
    return !ur::InverseKinematicsAll(model, base_T_tcp * tcp_T_flange).empty();
  };
}

Eigen::Isometry3d TcpPoseFromJoints(ur::ArmModel model, const ur::Joints& q,
                                    const Eigen::Isometry3d& flange_T_tcp) {
  return ur::ForwardKinematics(model, q) * flange_T_tcp;
}

BoxInBase BoxToBase(const DetectedBox& box, const Eigen::Isometry3d& base_T_camera,
                    const BoxDims& dims) {
  BoxInBase out;
  out.base_T_box = base_T_camera * box.camera_T_box;
  out.grasp_face = box.grasp_face;
  const int axis = static_cast<int>(box.grasp_face) / 2;
  out.depth_m = dims[axis];
  const Eigen::Vector3d box_n = BoxFaceNormal(box.grasp_face);
  out.grasp_normal = (out.base_T_box.linear() * box_n).normalized();
  out.grasp_point = out.base_T_box * (0.5 * out.depth_m * box_n);
  const double c = std::clamp(out.grasp_normal.z(), -1.0, 1.0);
  out.tilt_deg = std::acos(c) * 180.0 / 3.14159265358979323846;
  return out;
}

std::array<Eigen::Isometry3d, 4> GraspCandidates(const BoxInBase& box,
                                                 const Eigen::Quaterniond& base_R_tcp_now) {
  const int axis = static_cast<int>(box.grasp_face) / 2;
  const Eigen::Matrix3d& R = box.base_T_box.linear();
  const Eigen::Vector3d u = R.col((axis + 1) % 3);
  const Eigen::Vector3d v = R.col((axis + 2) % 3);
  const Eigen::Vector3d z = -box.grasp_normal;
  const std::array<Eigen::Vector3d, 4> xs = {u, v, -u, -v};
  std::array<Eigen::Isometry3d, 4> grasps;
  std::array<double, 4> angle;
  for (int i = 0; i < 4; ++i) {
    // Re-orthogonalise x against z: the box rotation is rigid, but rounding.
    const Eigen::Vector3d x = (xs[i] - xs[i].dot(z) * z).normalized();
    Eigen::Matrix3d base_R_tcp;
    base_R_tcp << x, z.cross(x), z;
    grasps[i] = Eigen::Isometry3d::Identity();
    grasps[i].linear() = base_R_tcp;
    grasps[i].translation() = box.grasp_point;
    angle[i] = ur::RotationAngleBetween(base_R_tcp_now, Eigen::Quaterniond(base_R_tcp));
  }
  std::array<int, 4> order = {0, 1, 2, 3};
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return angle[a] < angle[b]; });
  std::array<Eigen::Isometry3d, 4> sorted;
  for (int i = 0; i < 4; ++i) sorted[i] = grasps[order[i]];
  return sorted;
}

Eigen::Isometry3d RaisedAlongBaseZ(const Eigen::Isometry3d& pose, double height_m) {
  Eigen::Isometry3d raised = pose;
  raised.translation().z() += height_m;
  return raised;
}

}  // namespace cornerpose::robot_client
