#include "common/perception/floor_rest.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/perception/internal/hypothesis_judge.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace

absl::Status FloorRestOptions::Validate() const {
  for (absl::Status s : {CheckRange("floor_rest.max_tilt_deg", max_tilt_deg, 0.0, 30.0),
                         CheckRange("floor_rest.min_tilt_deg", min_tilt_deg, 0.0, 30.0),
                         CheckRange("floor_rest.min_dip_m", min_dip_m, 0.0, 0.1),
                         CheckPositive("floor_rest.max_gap_m", max_gap_m, 0.1)}) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

int RestOnFloor(const Eigen::Vector3d& floor_normal, const Eigen::Vector3d& floor_point,
                const BoxDims& dims, const FloorRestOptions& options,
                std::vector<DetectedBox>* boxes) {
  if (options.max_tilt_deg <= 0.0) return 0;
  const Eigen::Vector3d up = floor_normal.normalized();
  int turned = 0;
  for (DetectedBox& box : *boxes) {
    const Eigen::Matrix3d r = box.camera_T_box.linear();
    // The box axis nearest the floor's normal, turned up: its bottom faces
    // away from it, and within max_tilt_deg of the floor the lowest of the
    // box's corners is one of its bottom's.
    int axis = 0;
    for (int k = 1; k < 3; ++k) {
      if (std::abs(r.col(k).dot(up)) > std::abs(r.col(axis).dot(up))) axis = k;
    }
    const Eigen::Vector3d box_up = (r.col(axis).dot(up) > 0.0 ? 1.0 : -1.0) * r.col(axis);
    const double tilt_deg = std::acos(std::clamp(box_up.dot(up), -1.0, 1.0)) / kDeg;
    if (tilt_deg <= options.min_tilt_deg || tilt_deg > options.max_tilt_deg) continue;
    if (internal::CornerHeightsAbove(box.camera_T_box, dims, up, floor_point).lowest >
        -options.min_dip_m) {
      continue;
    }
    const Eigen::Matrix3d turn = Eigen::Quaterniond::FromTwoVectors(box_up, up).toRotationMatrix();
    Eigen::Isometry3d flat = box.camera_T_box;
    flat.linear() = turn * r;
    flat.translation() =
        box.grasp_centre_camera + turn * (box.camera_T_box.translation() - box.grasp_centre_camera);
    // Flat, its bottom's corners lie level, the lowest of its corners.
    if (std::abs(internal::CornerHeightsAbove(flat, dims, up, floor_point).lowest) >
        options.max_gap_m) {
      continue;
    }
    box.camera_T_box = flat;
    box.grasp_normal_camera = turn * box.grasp_normal_camera;
    ++turned;
  }
  return turned;
}

}  // namespace cornerpose
