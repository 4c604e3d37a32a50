#include "common/perception/neighbour_hypotheses.h"

#include <Eigen/Geometry>
#include <numbers>

namespace cornerpose {

std::vector<Eigen::Isometry3d> NeighbourHypotheses(const DetectedBox& box, const BoxDims& dims,
                                                   double gap_m, bool layer_down) {
  const int face = static_cast<int>(box.grasp_face);
  const int axis_n = face / 2, axis_a = (axis_n + 1) % 3, axis_b = (axis_n + 2) % 3;
  const Eigen::Matrix3d R = box.camera_T_box.linear();
  const Eigen::Vector3d t = box.camera_T_box.translation();
  // The same box turned a quarter about the face normal: its a and b sides
  // swap.
  Eigen::Matrix3d R_turned =
      R * Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::Unit(axis_n)).toRotationMatrix();
  std::vector<Eigen::Isometry3d> out;
  auto add = [&](const Eigen::Matrix3d& rot, const Eigen::Vector3d& centre) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = rot;
    pose.translation() = centre;
    out.push_back(pose);
  };
  const double A = dims[axis_a], B = dims[axis_b];
  // (direction across the side, half size of this box across it, half size
  // of this box along the side)
  struct Side {
    Eigen::Vector3d across, along;
    double half_across, half_along;
  };
  const Side sides[4] = {{R.col(axis_a), R.col(axis_b), A / 2, B / 2},
                         {-R.col(axis_a), R.col(axis_b), A / 2, B / 2},
                         {R.col(axis_b), R.col(axis_a), B / 2, A / 2},
                         {-R.col(axis_b), R.col(axis_a), B / 2, A / 2}};
  // A layer down: on a pallet stacked at two heights, the boxes of the lower
  // layer beside the upper one lie one box height below it (the grasp
  // face's normal, pointing out of the box, is up).
  const Eigen::Vector3d down = -(face % 2 == 0 ? 1.0 : -1.0) * dims[axis_n] * R.col(axis_n);
  for (const Side& s : sides) {
    // Same orientation: straight across, on its level and a layer down.
    add(R, t + (2 * s.half_across + gap_m) * s.across);
    if (layer_down) add(R, t + (2 * s.half_across + gap_m) * s.across + down);
    // Turned: across it the neighbour is half_along deep, along it
    // half_across long; flush with either end of the shared side.
    const double shift = s.half_along - s.half_across;
    for (double end : {-1.0, 1.0}) {
      add(R_turned, t + (s.half_across + s.half_along + gap_m) * s.across + end * shift * s.along);
    }
  }
  return out;
}

}  // namespace cornerpose
