// SlotPose: row-major within a layer, then layers up, in the origin's frame;
// RESOURCE_EXHAUSTED past the end.
#include "robot_client/planning/place_pattern.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace cornerpose::robot_client {
namespace {

using ::testing::HasSubstr;

PlacePatternOptions Pattern() {
  PlacePatternOptions p;
  p.base_T_origin.translation() = Eigen::Vector3d(-0.32, 0.40, 0.01);
  p.rows = 2;
  p.columns = 3;
  p.layers = 2;
  p.spacing_x_m = 0.32;
  p.spacing_y_m = 0.22;
  p.layer_height_m = 0.15;
  return p;
}

TEST(PlacePatternTest, SlotsFillRowsThenLayers) {
  const PlacePatternOptions p = Pattern();
  ASSERT_TRUE(p.Validate().ok());
  EXPECT_EQ(SlotCount(p), 12);
  const struct {
    int slot;
    Eigen::Vector3d position;
  } expected[] = {
      {0, {-0.32, 0.40, 0.01}}, {1, {0.00, 0.40, 0.01}},  {2, {0.32, 0.40, 0.01}},
      {3, {-0.32, 0.62, 0.01}}, {5, {0.32, 0.62, 0.01}},  {6, {-0.32, 0.40, 0.16}},
      {10, {0.00, 0.62, 0.16}}, {11, {0.32, 0.62, 0.16}},
  };
  for (const auto& e : expected) {
    SCOPED_TRACE(e.slot);
    absl::StatusOr<Eigen::Isometry3d> pose = SlotPose(p, e.slot);
    ASSERT_TRUE(pose.ok()) << pose.status();
    EXPECT_TRUE(pose->translation().isApprox(e.position, 1e-12)) << pose->translation().transpose();
    EXPECT_TRUE(pose->linear().isApprox(Eigen::Matrix3d::Identity()));
  }
}

TEST(PlacePatternTest, SpacingFollowsTheOriginsAxes) {
  PlacePatternOptions p = Pattern();
  // Turned 90 degrees: columns go along base +y, rows along base -x.
  p.base_T_origin.linear() =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  absl::StatusOr<Eigen::Isometry3d> pose = SlotPose(p, 1 + 3 + 6);  // column 1, row 1, layer 1
  ASSERT_TRUE(pose.ok()) << pose.status();
  EXPECT_TRUE(pose->translation().isApprox(Eigen::Vector3d(-0.32 - 0.22, 0.40 + 0.32, 0.16), 1e-12))
      << pose->translation().transpose();
  EXPECT_TRUE(pose->linear().isApprox(p.base_T_origin.linear()));
}

TEST(PlacePatternTest, PastTheEndIsExhausted) {
  const PlacePatternOptions p = Pattern();
  absl::StatusOr<Eigen::Isometry3d> pose = SlotPose(p, 12);
  EXPECT_EQ(pose.status().code(), absl::StatusCode::kResourceExhausted) << pose.status();
  EXPECT_THAT(pose.status().message(), HasSubstr("full"));
  EXPECT_EQ(SlotPose(p, 1000).status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(SlotPose(p, -1).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(PlacePatternTest, EmptyPatternHasNoSlots) {
  PlacePatternOptions p = Pattern();
  p.layers = 0;
  EXPECT_EQ(SlotCount(p), 0);
  EXPECT_EQ(SlotPose(p, 0).status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(p.Validate().message(), HasSubstr("no slots"));
}

}  // namespace
}  // namespace cornerpose::robot_client
