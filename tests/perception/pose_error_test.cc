#include "common/perception/pose_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace cornerpose {
namespace {

Eigen::Isometry3d SomePose() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(-0.3, Eigen::Vector3d(1, 2, 0).normalized()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(0.1, -0.05, 1.2);
  return pose;
}

// Rotates a pose about one of its own axes.
Eigen::Isometry3d RotatedAboutOwnAxis(const Eigen::Isometry3d& pose, double angle_rad,
                                      const Eigen::Vector3d& axis) {
  Eigen::Isometry3d out = pose;
  out.linear() = pose.linear() * Eigen::AngleAxisd(angle_rad, axis).toRotationMatrix();
  return out;
}

TEST(PoseErrorTest, SymmetryCounts) {
  EXPECT_EQ(BoxSymmetries({0.30, 0.20, 0.15}).size(), 4u);
  EXPECT_EQ(BoxSymmetries({0.25, 0.25, 0.20}).size(), 8u);
  EXPECT_EQ(BoxSymmetries({0.20, 0.30, 0.30}).size(), 8u);
  EXPECT_EQ(BoxSymmetries({0.20, 0.20, 0.20}).size(), 24u);
}

TEST(PoseErrorTest, SymmetriesAreProperSignedPermutations) {
  const BoxDims dims{0.25, 0.20, 0.25};
  for (const Eigen::Matrix3d& S : BoxSymmetries(dims)) {
    EXPECT_NEAR(S.determinant(), 1.0, 1e-12);
    EXPECT_TRUE((S * S.transpose()).isIdentity(1e-12));
    // It maps the half-extent vector onto itself up to signs.
    EXPECT_TRUE((S * dims.vec()).cwiseAbs().isApprox(dims.vec(), 1e-12));
  }
  EXPECT_TRUE(BoxSymmetries(dims).front().isIdentity());
}

TEST(PoseErrorTest, HalfTurnAboutZIsTheSamePose) {
  const BoxDims dims{0.30, 0.20, 0.15};
  const Eigen::Isometry3d a = SomePose();
  const Eigen::Isometry3d b = RotatedAboutOwnAxis(a, std::numbers::pi, Eigen::Vector3d::UnitZ());
  const PoseError error = ComparePoses(a, b, dims);
  EXPECT_NEAR(error.translation_m, 0.0, 1e-12);
  EXPECT_NEAR(error.rotation_deg, 0.0, 1e-6);
}

TEST(PoseErrorTest, QuarterYawDependsOnFootprint) {
  const Eigen::Isometry3d a = SomePose();
  const Eigen::Isometry3d b =
      RotatedAboutOwnAxis(a, std::numbers::pi / 2, Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(ComparePoses(a, b, {0.25, 0.25, 0.20}).rotation_deg, 0.0, 1e-6);
  EXPECT_NEAR(ComparePoses(a, b, {0.30, 0.20, 0.15}).rotation_deg, 90.0, 1e-6);
}

TEST(PoseErrorTest, SmallRotationGivesItsAngle) {
  const BoxDims dims{0.30, 0.20, 0.15};
  const Eigen::Isometry3d a = SomePose();
  for (double deg : {1e-4, 0.01, 0.5, 3.0, 20.0}) {
    const Eigen::Isometry3d b = RotatedAboutOwnAxis(a, deg * std::numbers::pi / 180.0,
                                                    Eigen::Vector3d(1, -1, 2).normalized());
    EXPECT_NEAR(RotationErrorDeg(a.linear(), b.linear(), dims), deg, 1e-6 * deg + 1e-9) << deg;
  }
}

TEST(PoseErrorTest, TranslationError) {
  Eigen::Isometry3d a = SomePose();
  Eigen::Isometry3d b = a;
  b.translation() += Eigen::Vector3d(0.003, -0.004, 0.0);
  EXPECT_NEAR(TranslationErrorM(a, b), 0.005, 1e-12);
  EXPECT_NEAR(ComparePoses(a, b, {0.3, 0.2, 0.15}).translation_m, 0.005, 1e-12);
}

}  // namespace
}  // namespace cornerpose
