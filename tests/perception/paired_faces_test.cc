// Pairs of boxes read side by side on one face whose faces together are
// another face of the box (internal::OneBoxForPair): carton_flat's top
// (0.30 x 0.20) is two of its sides (0.30 x 0.10) side by side. Boxes as
// the detector returns them, 1.5 m in front of the camera, their grasp face
// towards it.
#include "common/perception/internal/paired_faces.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <numbers>
#include <optional>

namespace cornerpose {
namespace {

constexpr BoxDims kCartonFlat{0.30, 0.20, 0.10};
constexpr double kTolerance = 0.025;
constexpr double kDeg = std::numbers::pi / 180.0;

// A box lying on its side (grasp face +y, 0.30 along the camera's x and the
// box's height across it, along the camera's y), its face centre at `top`,
// turned by turn_deg about the face's normal.
DetectedBox OnItsSide(const Eigen::Vector3d& top, const BoxDims& dims = kCartonFlat,
                      double turn_deg = 0.0) {
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d::UnitX();
  r.col(1) = -Eigen::Vector3d::UnitZ();  // +y towards the camera
  r.col(2) = r.col(0).cross(r.col(1));
  DetectedBox box;
  box.grasp_face = BoxFace::kPlusY;
  box.grasp_normal_camera = -Eigen::Vector3d::UnitZ();
  box.grasp_centre_camera = top;
  box.camera_T_box.linear() =
      Eigen::AngleAxisd(turn_deg * kDeg, box.grasp_normal_camera).toRotationMatrix() * r;
  box.camera_T_box.translation() = top - box.grasp_normal_camera * dims.b / 2.0;
  return box;
}

const Eigen::Vector3d kTop(0.1, 0.05, 1.5);

TEST(PairedFacesTest, TwoSidesSideBySideAreTheTopOfOneBox) {
  const DetectedBox x = OnItsSide(kTop), y = OnItsSide(kTop + Eigen::Vector3d(0.0, 0.10, 0.0));
  for (const auto& [p, q] : {std::pair{x, y}, std::pair{y, x}}) {
    const std::optional<Eigen::Isometry3d> one =
        internal::OneBoxForPair(p, q, kCartonFlat, kTolerance);
    ASSERT_TRUE(one.has_value());
    // One carton lying flat: its top (0.30 x 0.20) the pair's two faces,
    // its centre half its height (0.10) behind their middle.
    EXPECT_TRUE(one->translation().isApprox(Eigen::Vector3d(0.1, 0.10, 1.55), 1e-9))
        << one->translation().transpose();
    const Eigen::Matrix3d r = one->linear();
    EXPECT_NEAR(std::abs(r.col(2).dot(Eigen::Vector3d::UnitZ())), 1.0, 1e-9);  // z: the height
    EXPECT_NEAR(std::abs(r.col(0).dot(Eigen::Vector3d::UnitX())), 1.0, 1e-9);  // l along the pair
    EXPECT_NEAR(r.determinant(), 1.0, 1e-9);
  }
  // Within the tolerance: 1.5 cm apart past touching, 1 cm out of line.
  EXPECT_TRUE(internal::OneBoxForPair(x, OnItsSide(kTop + Eigen::Vector3d(0.01, 0.115, 0.0)),
                                      kCartonFlat, kTolerance)
                  .has_value());
}

TEST(PairedFacesTest, BoxesThatAreNoSuchPairAreNone) {
  auto none = [](const DetectedBox& y, const BoxDims& dims = kCartonFlat) {
    return !internal::OneBoxForPair(OnItsSide(kTop, dims), y, dims, kTolerance).has_value();
  };
  // 3 cm apart: two boxes with a gap between them.
  EXPECT_TRUE(none(OnItsSide(kTop + Eigen::Vector3d(0.0, 0.13, 0.0))));
  // Set off by 3 cm along the pair's length, or 3 cm nearer the camera.
  EXPECT_TRUE(none(OnItsSide(kTop + Eigen::Vector3d(0.03, 0.10, 0.0))));
  EXPECT_TRUE(none(OnItsSide(kTop + Eigen::Vector3d(0.0, 0.10, -0.03))));
  // Turned 10 degrees against it.
  EXPECT_TRUE(none(OnItsSide(kTop + Eigen::Vector3d(0.0, 0.10, 0.0), kCartonFlat, 10.0)));
  // End to end: 0.60 x 0.10 is no face of the box.
  EXPECT_TRUE(none(OnItsSide(kTop + Eigen::Vector3d(0.30, 0.0, 0.0))));
  // carton_s (0.30 x 0.20 x 0.15): two sides make 0.30 x 0.30, no face.
  const BoxDims carton_s{0.30, 0.20, 0.15};
  EXPECT_TRUE(none(OnItsSide(kTop + Eigen::Vector3d(0.0, 0.15, 0.0), carton_s), carton_s));
  // Read on different faces.
  DetectedBox flat = OnItsSide(kTop + Eigen::Vector3d(0.0, 0.10, 0.0));
  flat.grasp_face = BoxFace::kPlusZ;
  EXPECT_TRUE(none(flat));
}

}  // namespace
}  // namespace cornerpose
