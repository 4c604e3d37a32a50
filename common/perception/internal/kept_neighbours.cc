#include "common/perception/internal/kept_neighbours.h"

#include <cmath>
#include <numbers>

namespace cornerpose::internal {
namespace {

constexpr double kProbeM = 0.02;    // how far past and before the side the face is probed
constexpr double kInsideM = 0.005;  // a probe this far inside the kept face's outline
constexpr double kPlaneM = 0.015;   // the kept face's plane from the side
constexpr double kPlaneDeg = 8.0;   // ... and from the face's plane
constexpr double kAlignDeg = 5.0;   // the kept box's sides from this side

double CosDeg(double deg) { return std::cos(deg * std::numbers::pi / 180.0); }

// Whether camera point q lies on kept box k's grasp face, at least `inset`
// inside its outline (negative: that far outside it still counts).
bool OnKeptFace(const DetectedBox& k, const BoxDims& dims, const Eigen::Vector3d& q, double inset) {
  const int n = static_cast<int>(k.grasp_face) / 2;
  const Eigen::Vector3d local = k.camera_T_box.inverse() * q;
  for (int i = 0; i < 3; ++i) {
    if (i == n) continue;
    if (std::abs(local[i]) > 0.5 * dims[i] - inset) return false;
  }
  return std::abs((q - k.grasp_centre_camera).dot(k.grasp_normal_camera)) <= kPlaneM;
}

}  // namespace

bool SideAgainstKeptBox(const Eigen::Isometry3d& camera_T_box, BoxFace grasp, const BoxDims& dims,
                        int side, const std::vector<DetectedBox>& kept) {
  const int fi = static_cast<int>(grasp), n = fi / 2;
  const int here = side < 2 ? (n + 1) % 3 : (n + 2) % 3;
  const int along = side < 2 ? (n + 2) % 3 : (n + 1) % 3;
  const double sign = side % 2 == 0 ? 1.0 : -1.0;
  const Eigen::Matrix3d R = camera_T_box.linear();
  const Eigen::Vector3d normal = R * BoxFaceNormal(grasp);
  const Eigen::Vector3d along_dir = R.col(along);
  for (const DetectedBox& k : kept) {
    if (k.grasp_normal_camera.dot(normal) < CosDeg(kPlaneDeg)) continue;
    // One of the kept box's in-plane axes along this side.
    const int kn = static_cast<int>(k.grasp_face) / 2;
    bool aligned = false;
    for (int i = 0; i < 3; ++i) {
      if (i != kn && std::abs(k.camera_T_box.linear().col(i).dot(along_dir)) >= CosDeg(kAlignDeg)) {
        aligned = true;
      }
    }
    if (!aligned) continue;
    bool against = true;
    for (const double t : {-0.3, 0.0, 0.3}) {
      Eigen::Vector3d local = Eigen::Vector3d::Zero();
      local[n] = (fi % 2 == 0 ? 0.5 : -0.5) * dims[n];
      local[along] = t * dims[along];
      local[here] = sign * (0.5 * dims[here] + kProbeM);
      const Eigen::Vector3d past = camera_T_box * local;
      local[here] = sign * (0.5 * dims[here] - kProbeM);
      const Eigen::Vector3d before = camera_T_box * local;
      if (!OnKeptFace(k, dims, past, kInsideM) || OnKeptFace(k, dims, before, -kInsideM)) {
        against = false;
        break;
      }
    }
    if (against) return true;
  }
  return false;
}

}  // namespace cornerpose::internal
