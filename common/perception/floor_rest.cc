#include "common/perception/floor_rest.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Heights above the floor of the four corners of the box's face with
// outward normal `down` (a box-frame axis, signed).
std::array<double, 4> FaceCornerHeights(const Eigen::Isometry3d& pose, const BoxDims& dims,
                                        int axis, double sign, const Eigen::Vector3d& normal,
                                        const Eigen::Vector3d& on_floor) {
  std::array<double, 4> h{};
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  int k = 0;
  for (const double sa : {-0.5, 0.5}) {
    for (const double sb : {-0.5, 0.5}) {
      Eigen::Vector3d local = Eigen::Vector3d::Zero();
      local[axis] = 0.5 * sign * dims[axis];
      local[a] = sa * dims[a];
      local[b] = sb * dims[b];
      h[k++] = normal.dot(pose * local - on_floor);
    }
  }
  return h;
}

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
    // The box axis nearest the floor's normal; the bottom face is the one
    // facing away from it.
    int axis = 0;
    for (int k = 1; k < 3; ++k) {
      if (std::abs(r.col(k).dot(up)) > std::abs(r.col(axis).dot(up))) axis = k;
    }
    const double sign = r.col(axis).dot(up) > 0.0 ? -1.0 : 1.0;  // the bottom's outward normal
    const Eigen::Vector3d box_up = -sign * r.col(axis);
    const double tilt_deg = std::acos(std::clamp(box_up.dot(up), -1.0, 1.0)) / kDeg;
    if (tilt_deg <= options.min_tilt_deg || tilt_deg > options.max_tilt_deg) continue;
    const std::array<double, 4> before =
        FaceCornerHeights(box.camera_T_box, dims, axis, sign, up, floor_point);
    if (*std::min_element(before.begin(), before.end()) > -options.min_dip_m) continue;
    const Eigen::Matrix3d turn = Eigen::Quaterniond::FromTwoVectors(box_up, up).toRotationMatrix();
    Eigen::Isometry3d flat = box.camera_T_box;
    flat.linear() = turn * r;
    flat.translation() =
        box.grasp_centre_camera + turn * (box.camera_T_box.translation() - box.grasp_centre_camera);
    const std::array<double, 4> after = FaceCornerHeights(flat, dims, axis, sign, up, floor_point);
    if (std::any_of(after.begin(), after.end(),
                    [&](double h) { return std::abs(h) > options.max_gap_m; })) {
      continue;
    }
    box.camera_T_box = flat;
    box.grasp_normal_camera = turn * box.grasp_normal_camera;
    ++turned;
  }
  return turned;
}

}  // namespace cornerpose
