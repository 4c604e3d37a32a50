#include "common/perception/internal/paired_faces.h"

#include <cmath>
#include <numbers>

#include "common/perception/internal/grasp_face.h"

namespace cornerpose::internal {
namespace {

constexpr double kPlaneM = 0.015;
constexpr double kPlaneDeg = 8.0;
constexpr double kAlignDeg = 5.0;

double CosDeg(double deg) { return std::cos(deg * std::numbers::pi / 180.0); }

}  // namespace

std::optional<Eigen::Isometry3d> OneBoxForPair(const DetectedBox& x, const DetectedBox& y,
                                               const BoxDims& dims, double tolerance_m) {
  const int axis_n = static_cast<int>(x.grasp_face) / 2;
  if (static_cast<int>(y.grasp_face) / 2 != axis_n) return std::nullopt;
  const GraspFace fx = GraspFaceOf(x, dims), fy = GraspFaceOf(y, dims);
  if (!FacesOnOnePlane(fx, fy, CosDeg(kPlaneDeg), kPlaneM)) return std::nullopt;
  if (std::abs(fx.a.dot(fy.a)) < CosDeg(kAlignDeg)) return std::nullopt;
  const Eigen::Vector3d d = fy.c - fx.c;
  // Along which in-plane axis the two lie, one face width apart.
  for (const bool along_a : {true, false}) {
    const Eigen::Vector3d& step = along_a ? fx.a : fx.b;
    const Eigen::Vector3d& across = along_a ? fx.b : fx.a;
    const double width = 2.0 * (along_a ? fx.half_a : fx.half_b);
    const double length = 2.0 * (along_a ? fx.half_b : fx.half_a);
    if (std::abs(std::abs(d.dot(step)) - width) > tolerance_m ||
        std::abs(d.dot(across)) > tolerance_m) {
      continue;
    }
    // Together: 2 * width along `step`, length along `across`. Which other
    // face of the box is that rectangle?
    for (int m = 0; m < 3; ++m) {
      if (m == axis_n) continue;
      const int m1 = (m + 1) % 3, m2 = (m + 2) % 3;
      for (const bool step_on_m1 : {true, false}) {
        const double along_step = step_on_m1 ? dims[m1] : dims[m2];
        const double along_across = step_on_m1 ? dims[m2] : dims[m1];
        if (std::abs(along_step - 2.0 * width) > tolerance_m ||
            std::abs(along_across - length) > tolerance_m) {
          continue;
        }
        Eigen::Matrix3d r;
        r.col(m1) = step_on_m1 ? step : across;
        r.col(m2) = step_on_m1 ? across : step;
        r.col(m) = r.col(m1).cross(r.col(m2));  // (m1, m2, m) is cyclic: right-handed
        const Eigen::Vector3d outward = (r.col(m).dot(fx.n) >= 0.0 ? 1.0 : -1.0) * r.col(m);
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.linear() = r;
        pose.translation() = 0.5 * (fx.c + fy.c) - 0.5 * dims[m] * outward;
        return pose;
      }
    }
  }
  return std::nullopt;
}

}  // namespace cornerpose::internal
