// Faces between two parallel edge segments (ProposeFromEdgePairs): the two
// long sides of a brick's top propose the brick, at either end of what they
// span; segments that are not a face's opposite sides propose nothing.
#include "common/perception/edge_pair_faces.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "common/perception/box_pose.h"
#include "common/perception/pose_error.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kBrick{0.19, 0.09, 0.057};

// A brick lying flat 1.2 m in front of the camera, its top (+z) towards
// it, turned 30 degrees about the optical axis and 1 cm left of it.
Eigen::Isometry3d Brick() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(30.0 * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(-0.01, 0.02, 1.2 + kBrick.h / 2);
  return pose;
}

// The segment along the top's side at y = side * b/2 (box frame), from
// x = from to x = to.
EdgeSegment Side(const Eigen::Isometry3d& pose, double side, double from, double to) {
  EdgeSegment s;
  s.end1 = (pose * Eigen::Vector3d(from, side * kBrick.b / 2, kBrick.h / 2)).cast<float>();
  s.end2 = (pose * Eigen::Vector3d(to, side * kBrick.b / 2, kBrick.h / 2)).cast<float>();
  s.direction = (s.end2 - s.end1).normalized();
  s.point = s.end1;
  s.num_points = 40;
  return s;
}

bool Proposes(const std::vector<EdgePairFace>& faces, const Eigen::Isometry3d& truth) {
  for (const EdgePairFace& f : faces) {
    const PoseError e = ComparePoses(f.camera_T_box, truth, kBrick);
    if (e.translation_m < 0.005 && e.rotation_deg < 1.0) return true;
  }
  return false;
}

TEST(EdgePairFacesTest, TheLongSidesOfABricksTopProposeTheBrick) {
  const Eigen::Isometry3d brick = Brick();
  const double half = kBrick.l / 2;
  // Both sides seen end to end, one of them drawn end2 -> end1.
  const std::vector<EdgeSegment> whole = {Side(brick, 1, -half, half),
                                          Side(brick, -1, half, -half)};
  const std::vector<EdgePairFace> faces = ProposeFromEdgePairs(whole, kBrick, EdgePairOptions{});
  EXPECT_TRUE(Proposes(faces, brick));
  for (const EdgePairFace& f : faces) {
    EXPECT_EQ(f.segment_a, 0);
    EXPECT_EQ(f.segment_b, 1);
  }
  // The far end hidden (the sides seen over 12 and 14 cm from the near
  // end): anchored at the end they show, the brick again.
  const std::vector<EdgeSegment> near_end = {Side(brick, 1, -half, -half + 0.12),
                                             Side(brick, -1, -half, -half + 0.14)};
  EXPECT_TRUE(Proposes(ProposeFromEdgePairs(near_end, kBrick, EdgePairOptions{}), brick));
  // ... and the near end hidden.
  const std::vector<EdgeSegment> far_end = {Side(brick, 1, half - 0.12, half),
                                            Side(brick, -1, half - 0.13, half)};
  EXPECT_TRUE(Proposes(ProposeFromEdgePairs(far_end, kBrick, EdgePairOptions{}), brick));
}

TEST(EdgePairFacesTest, SegmentsThatAreNoFacesOppositeSidesProposeNothing) {
  const Eigen::Isometry3d brick = Brick();
  const double half = kBrick.l / 2;
  const EdgeSegment a = Side(brick, 1, -half, half);
  // Longer than any side of the box (by more than length_tolerance_m).
  EXPECT_TRUE(ProposeFromEdgePairs({Side(brick, 1, -0.12, 0.12), Side(brick, -1, -0.12, 0.12)},
                                   kBrick, EdgePairOptions{})
                  .empty());
  // Turned 20 degrees against the other.
  EdgeSegment turned = Side(brick, -1, -half, half);
  const Eigen::Vector3f mid = (turned.end1 + turned.end2) / 2;
  const Eigen::Matrix3f r = Eigen::AngleAxisf(20.0f * std::numbers::pi_v<float> / 180.0f,
                                              brick.linear().col(2).cast<float>())
                                .toRotationMatrix();
  turned.end1 = mid + r * (turned.end1 - mid);
  turned.end2 = mid + r * (turned.end2 - mid);
  EXPECT_TRUE(ProposeFromEdgePairs({a, turned}, kBrick, EdgePairOptions{}).empty());
  // Side by side along their line, not facing each other.
  EXPECT_TRUE(ProposeFromEdgePairs({Side(brick, 1, -half, -0.01), Side(brick, -1, 0.01, half)},
                                   kBrick, EdgePairOptions{})
                  .empty());
  // 12 cm apart: no side of the brick (9 cm is 3 cm off).
  EdgeSegment far = Side(brick, -1, -half, half);
  const Eigen::Vector3f away = (far.end1 - a.end1).normalized() * 0.03f;
  far.end1 += away;
  far.end2 += away;
  EXPECT_TRUE(ProposeFromEdgePairs({a, far}, kBrick, EdgePairOptions{}).empty());
  // A segment with no coordinates (NaN) pairs with nothing.
  EdgeSegment nan = Side(brick, -1, -half, half);
  nan.end1.x() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(ProposeFromEdgePairs({a, nan}, kBrick, EdgePairOptions{}).empty());
  // Off: nothing, even from the brick's own sides.
  EdgePairOptions off;
  off.enabled = false;
  EXPECT_TRUE(ProposeFromEdgePairs({a, Side(brick, -1, -half, half)}, kBrick, off).empty());
}

TEST(EdgePairFacesTest, OptionsOutOfRangeNameTheirField) {
  EXPECT_TRUE(EdgePairOptions{}.Validate().ok());
  EdgePairOptions o;
  o.max_angle_deg = 60.0;
  EXPECT_NE(o.Validate().message().find("edge_pairs.max_angle_deg"), std::string::npos);
  o = EdgePairOptions{};
  o.width_tolerance_m = 0.0;
  EXPECT_NE(o.Validate().message().find("edge_pairs.width_tolerance_m"), std::string::npos);
  o = EdgePairOptions{};
  o.min_overlap = 1.5;
  EXPECT_NE(o.Validate().message().find("edge_pairs.min_overlap"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose::testing
