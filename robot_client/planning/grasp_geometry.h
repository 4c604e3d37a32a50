// The geometry shared by pick selection and pick planning: a detected box in
// the robot base frame, the suction grasps on its face, and reachability.
//
// Frames: base = the UR controller's base frame (z up); box = the detector's
// box frame (origin at the centroid, x along l, y along b, z along h); tcp =
// the suction cup's tip with tool z pointing out of the cup, into the face
// it holds. Metres and radians.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <limits>

#include "common/box/box_types.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::robot_client {

// Whether the arm can put its TCP at base_T_tcp (inverse kinematics).
using Reachability = std::function<bool(const Eigen::Isometry3d& base_T_tcp)>;

// Reachable when the closed-form inverse kinematics of `model` has a solution
// for base_T_tcp * flange_T_tcp^-1 within the joint limits.
Reachability MakeIkReachability(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp);

// The TCP pose of joint state q: FK(q) * flange_T_tcp (the waypoint I).
Eigen::Isometry3d TcpPoseFromJoints(ur::ArmModel model, const ur::Joints& q,
                                    const Eigen::Isometry3d& flange_T_tcp);

// A detected box in the base frame.
struct BoxInBase {
  Eigen::Isometry3d base_T_box = Eigen::Isometry3d::Identity();
  BoxFace grasp_face = BoxFace::kPlusZ;
  // Centre of the grasp face, metres, and its outward unit normal.
  Eigen::Vector3d grasp_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d grasp_normal = Eigen::Vector3d::UnitZ();
  // The box's size along the grasp normal (grasp face to opposite face), m.
  double depth_m = 0.0;
  // Angle between grasp_normal and base +z, degrees.
  double tilt_deg = 0.0;
  // The pile's top in the frame this box came from: the highest point of
  // any detected box, base z, metres (SelectPick sets it); NaN = unknown,
  // and the planner then uses the fixed waypoint heights.
  double pile_top_z_m = std::numeric_limits<double>::quiet_NaN();
};

// camera_T_box and the grasp face of `box`, moved to the base frame; the
// grasp point is the face centre of a box of size `dims`.
BoxInBase BoxToBase(const DetectedBox& box, const Eigen::Isometry3d& base_T_camera,
                    const BoxDims& dims);

// The four suction grasps of the box's grasp face: TCP at the face centre,
// tool z along -grasp_normal (into the face), tool x along +u, +v, -u, -v
// where u, v are the face's in-plane box axes (the box's symmetry makes them
// equivalent). Sorted by the rotation angle from `base_R_tcp_now` (the
// current TCP orientation), smallest first: the least wrist rotation.
std::array<Eigen::Isometry3d, 4> GraspCandidates(const BoxInBase& box,
                                                 const Eigen::Quaterniond& base_R_tcp_now);

// `pose` moved by height_m along base +z (orientation kept): M and R from G,
// place_above from F.
Eigen::Isometry3d RaisedAlongBaseZ(const Eigen::Isometry3d& pose, double height_m);

}  // namespace cornerpose::robot_client
