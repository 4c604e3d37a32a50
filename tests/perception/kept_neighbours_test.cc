// A side of a hypothesis's face against a box already kept
// (internal/kept_neighbours.h): only a coplanar, aligned box whose face
// begins where this one ends vouches for a seam there.
#include "common/perception/internal/kept_neighbours.h"

#include <gtest/gtest.h>

#include <numbers>

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonL{0.40, 0.30, 0.25};

// A carton lying flat 1.2 m in front of the camera, its top (+z) facing it.
Eigen::Isometry3d FlatCarton(const Eigen::Vector3d& centre) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  pose.translation() = centre;
  return pose;
}

DetectedBox Kept(const Eigen::Isometry3d& pose) {
  DetectedBox k;
  k.camera_T_box = pose;
  k.grasp_face = BoxFace::kPlusZ;
  k.grasp_normal_camera = pose.linear() * BoxFaceNormal(BoxFace::kPlusZ);
  k.grasp_centre_camera = pose * Eigen::Vector3d(0.0, 0.0, kCartonL.h / 2.0);
  return k;
}

bool Against(const Eigen::Isometry3d& pose, int side, const std::vector<DetectedBox>& kept) {
  return internal::SideAgainstKeptBox(pose, BoxFace::kPlusZ, kCartonL, side, kept);
}

// The box beside a kept one along its 0.4 m side, 3 mm apart: its -a side
// (toward the kept box) lies against it; its other sides do not.
TEST(KeptNeighboursTest, TheSideTowardATouchingKeptBoxLiesAgainstIt) {
  const std::vector<DetectedBox> kept{Kept(FlatCarton({0.0, 0.0, 1.2}))};
  const Eigen::Isometry3d beside = FlatCarton({0.403, 0.0, 1.2});
  EXPECT_TRUE(Against(beside, 1, kept));
  EXPECT_FALSE(Against(beside, 0, kept));
  EXPECT_FALSE(Against(beside, 2, kept));
  EXPECT_FALSE(Against(beside, 3, kept));
  // Across the 0.3 m side: its -b side (box -y, camera +y) faces it.
  const Eigen::Isometry3d below = FlatCarton({0.0, -0.303, 1.2});
  EXPECT_TRUE(Against(below, 2, kept) || Against(below, 3, kept));
  EXPECT_TRUE(Against(below, 2, kept) != Against(below, 3, kept));
  EXPECT_FALSE(Against(beside, 1, {}));
}

// Not against it: 5 cm of gap between them, 5 cm into it (overlapping),
// 3 cm higher (another layer), or turned 10 degrees.
TEST(KeptNeighboursTest, ABoxApartOverlappingHigherOrTurnedDoesNotVouch) {
  const std::vector<DetectedBox> kept{Kept(FlatCarton({0.0, 0.0, 1.2}))};
  EXPECT_FALSE(Against(FlatCarton({0.45, 0.0, 1.2}), 1, kept));
  EXPECT_FALSE(Against(FlatCarton({0.35, 0.0, 1.2}), 1, kept));
  EXPECT_FALSE(Against(FlatCarton({0.403, 0.0, 1.17}), 1, kept));
  Eigen::Isometry3d turned = FlatCarton({0.403, 0.0, 1.2});
  turned.linear() =
      turned.linear() * Eigen::AngleAxisd(10.0 * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ())
                            .toRotationMatrix();
  EXPECT_FALSE(Against(turned, 1, kept));
}

}  // namespace
}  // namespace cornerpose::testing
