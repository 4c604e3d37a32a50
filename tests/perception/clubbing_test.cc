#include "common/perception/clubbing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace cornerpose {
namespace {

EdgeSegment MakeSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  EdgeSegment s;
  s.end1 = a.cast<float>();
  s.end2 = b.cast<float>();
  s.point = (0.5 * (a + b)).cast<float>();
  s.direction = (b - a).normalized().cast<float>();
  s.num_points = static_cast<int>(1000 * (b - a).norm());
  return s;
}

// A tilted frame in front of the camera: u, v span a box face, n its normal.
struct Frame {
  Eigen::Vector3d origin{0.1, -0.05, 1.2};
  Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                       Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()))
                          .toRotationMatrix();
  Eigen::Vector3d u() const { return R.col(0); }
  Eigen::Vector3d v() const { return R.col(1); }
  Eigen::Vector3d n() const { return R.col(2); }
  Eigen::Vector3d At(double a, double b, double c = 0.0) const {
    return origin + a * u() + b * v() + c * n();
  }
};

TEST(SegmentsMeetTest, PerpendicularSegmentsMeetAtTheCorner) {
  const Frame f;
  // Both segments stop 1-2 cm short of the corner, as edge bands do, and
  // their lines pass 4 mm apart (the depth noise of one edge band).
  const std::vector<EdgeSegment> segments = {
      MakeSegment(f.At(0.012, 0), f.At(0.30, 0)),
      MakeSegment(f.At(0, 0.2, 0.004), f.At(0, 0.018, 0.004))};
  Corner corner;
  ASSERT_TRUE(SegmentsMeet(segments, 0, 1, ClubbingOptions{}, &corner));
  EXPECT_LT((corner.position.cast<double>() - f.At(0, 0)).norm(), 0.005);
  EXPECT_EQ(corner.segment_a, 0);
  EXPECT_EQ(corner.segment_b, 1);
  EXPECT_TRUE(corner.a_at_end1);   // end1 of segment 0 is at the corner
  EXPECT_FALSE(corner.b_at_end1);  // end2 of segment 1 is

  const absl::StatusOr<SegmentGroups> groups = ClubSegments(segments, ClubbingOptions{});
  ASSERT_TRUE(groups.ok()) << groups.status();
  ASSERT_EQ(groups->corners.size(), 1u);
  EXPECT_LT((groups->corners[0].position.cast<double>() - f.At(0, 0)).norm(), 0.005);
  ASSERT_EQ(groups->groups.size(), 1u);
  EXPECT_EQ(groups->groups[0], (std::vector<int>{0, 1}));
}

TEST(SegmentsMeetTest, ParallelSegmentsDoNotMeet) {
  const Frame f;
  // Side by side, and end to end: neither is a corner.
  const std::vector<EdgeSegment> segments = {MakeSegment(f.At(0, 0), f.At(0.3, 0)),
                                             MakeSegment(f.At(0, 0.005), f.At(0.3, 0.005)),
                                             MakeSegment(f.At(0.31, 0), f.At(0.5, 0))};
  Corner corner;
  EXPECT_FALSE(SegmentsMeet(segments, 0, 1, ClubbingOptions{}, &corner));
  EXPECT_FALSE(SegmentsMeet(segments, 0, 2, ClubbingOptions{}, &corner));
  const absl::StatusOr<SegmentGroups> groups = ClubSegments(segments, ClubbingOptions{});
  ASSERT_TRUE(groups.ok());
  EXPECT_TRUE(groups->corners.empty());
  EXPECT_TRUE(groups->groups.empty());
}

TEST(SegmentsMeetTest, PerpendicularLinesThreeCentimetresApartDoNotMeet) {
  const Frame f;
  // Seen from the camera they cross at the corner, but one lies 3 cm off
  // along the face's normal, 28 degrees from the line of sight: 1.4 cm
  // across it, more than meet_distance_m.
  const std::vector<EdgeSegment> segments = {MakeSegment(f.At(0, 0), f.At(0.3, 0)),
                                             MakeSegment(f.At(0, 0, 0.03), f.At(0, 0.2, 0.03))};
  ASSERT_NEAR(f.n().dot(f.origin.normalized()), 0.884, 0.01);
  Corner corner;
  EXPECT_FALSE(SegmentsMeet(segments, 0, 1, ClubbingOptions{}, &corner));
  // Within meet_distance_m they would.
  ClubbingOptions loose;
  loose.meet_distance_m = 0.035;
  EXPECT_TRUE(SegmentsMeet(segments, 0, 1, loose, &corner));
}

TEST(SegmentsMeetTest, DepthNoiseAlongTheLineOfSightStillMeets) {
  // A face seen head on: its normal along the line of sight to the corner,
  // where an active stereo camera's depth noise puts one edge's line 2 cm
  // behind the other's.
  const Eigen::Vector3d corner_at(0.2, -0.1, 1.6);
  const Eigen::Vector3d n = -corner_at.normalized();
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  const std::vector<EdgeSegment> segments = {
      MakeSegment(corner_at + 0.01 * u, corner_at + 0.19 * u),
      MakeSegment(corner_at - 0.02 * n + 0.01 * v, corner_at - 0.02 * n + 0.09 * v)};
  Corner corner;
  ASSERT_TRUE(SegmentsMeet(segments, 0, 1, ClubbingOptions{}, &corner));
  EXPECT_LT((corner.position.cast<double>() - (corner_at - 0.01 * n)).norm(), 0.002);
  // The paper's sphere (factor 1) does not take it; 4 cm apart, past three
  // times meet_distance_m, neither does the default.
  ClubbingOptions sphere;
  sphere.meet_along_view_factor = 1.0;
  EXPECT_FALSE(SegmentsMeet(segments, 0, 1, sphere, &corner));
  const std::vector<EdgeSegment> far = {
      segments[0], MakeSegment(corner_at - 0.04 * n + 0.01 * v, corner_at - 0.04 * n + 0.09 * v)};
  EXPECT_FALSE(SegmentsMeet(far, 0, 1, ClubbingOptions{}, &corner));
}

TEST(SegmentsMeetTest, AGapAcrossTheLineOfSightIsNotDepthNoise) {
  // A face seen edge on (its normal across the line of sight): 2 cm along
  // the normal is 2 cm across the view, and the lines do not meet.
  const Eigen::Vector3d corner_at(0.0, 0.0, 1.5);
  const Eigen::Vector3d n = Eigen::Vector3d::UnitX(), u = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d v = n.cross(u);
  const std::vector<EdgeSegment> segments = {
      MakeSegment(corner_at + 0.01 * u, corner_at + 0.19 * u),
      MakeSegment(corner_at + 0.02 * n + 0.01 * v, corner_at + 0.02 * n + 0.09 * v)};
  Corner corner;
  EXPECT_FALSE(SegmentsMeet(segments, 0, 1, ClubbingOptions{}, &corner));
}

TEST(ClubbingOptionsTest, ValidateNamesTheAlongViewFactor) {
  ClubbingOptions o;
  o.meet_along_view_factor = 0.5;
  const absl::Status s = o.Validate();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("meet_along_view_factor"), std::string::npos) << s;
}

TEST(SegmentsMeetTest, LinesThatCrossFarFromBothEndsDoNotMeet) {
  const Frame f;
  // A T: segment 1 would meet segment 0's line in its middle.
  const std::vector<EdgeSegment> t_junction = {MakeSegment(f.At(0, 0), f.At(0.3, 0)),
                                               MakeSegment(f.At(0.15, 0.01), f.At(0.15, 0.2))};
  Corner corner;
  EXPECT_FALSE(SegmentsMeet(t_junction, 0, 1, ClubbingOptions{}, &corner));
  // Both stop 5 cm short of the crossing: too far for end_gap_m = 3 cm.
  const std::vector<EdgeSegment> apart = {MakeSegment(f.At(0.05, 0), f.At(0.3, 0)),
                                          MakeSegment(f.At(0, 0.05), f.At(0, 0.2))};
  EXPECT_FALSE(SegmentsMeet(apart, 0, 1, ClubbingOptions{}, &corner));
}

TEST(SegmentsMeetTest, AngleTolerance) {
  const Frame f;
  auto at_angle = [&](double deg) {
    const double rad = deg * std::numbers::pi / 180.0;
    const Eigen::Vector3d dir = std::cos(rad) * f.u() + std::sin(rad) * f.v();
    return std::vector<EdgeSegment>{MakeSegment(f.At(0, 0), f.At(0.3, 0)),
                                    MakeSegment(f.At(0, 0) + 0.01 * dir, f.At(0, 0) + 0.2 * dir)};
  };
  Corner corner;
  EXPECT_TRUE(SegmentsMeet(at_angle(90.0), 0, 1, ClubbingOptions{}, &corner));
  EXPECT_TRUE(SegmentsMeet(at_angle(84.0), 0, 1, ClubbingOptions{}, &corner));
  EXPECT_TRUE(SegmentsMeet(at_angle(96.0), 0, 1, ClubbingOptions{}, &corner));
  EXPECT_FALSE(SegmentsMeet(at_angle(75.0), 0, 1, ClubbingOptions{}, &corner));
  EXPECT_FALSE(SegmentsMeet(at_angle(105.0), 0, 1, ClubbingOptions{}, &corner));
}

TEST(ClubSegmentsTest, AnLAndAFarSegmentGiveOneGroupOfTwo) {
  const Frame f;
  const std::vector<EdgeSegment> segments = {
      MakeSegment(f.At(0.5, 0.5), f.At(0.8, 0.5)),  // far away, alone
      MakeSegment(f.At(0.01, 0), f.At(0.3, 0)), MakeSegment(f.At(0, 0.015), f.At(0, 0.2))};
  const absl::StatusOr<SegmentGroups> groups = ClubSegments(segments, ClubbingOptions{});
  ASSERT_TRUE(groups.ok()) << groups.status();
  ASSERT_EQ(groups->groups.size(), 1u);
  EXPECT_EQ(groups->groups[0], (std::vector<int>{1, 2}));
  ASSERT_EQ(groups->corners.size(), 1u);
  EXPECT_LT((groups->corners[0].position.cast<double>() - f.At(0, 0)).norm(), 0.005);
}

TEST(ClubSegmentsTest, ARectangleIsOneGroupOfFourWithFourCorners) {
  const Frame f;
  const std::array<Eigen::Vector3d, 4> corners = {f.At(0, 0), f.At(0.3, 0), f.At(0.3, 0.2),
                                                  f.At(0, 0.2)};
  // Each side shortened by 1.5 cm at both ends (what the segment fitter
  // leaves next to an already removed perpendicular side).
  std::vector<EdgeSegment> segments;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& a = corners[k];
    const Eigen::Vector3d& b = corners[(k + 1) % 4];
    const Eigen::Vector3d d = (b - a).normalized();
    segments.push_back(MakeSegment(a + 0.015 * d, b - 0.015 * d));
  }
  const absl::StatusOr<SegmentGroups> groups = ClubSegments(segments, ClubbingOptions{});
  ASSERT_TRUE(groups.ok()) << groups.status();
  ASSERT_EQ(groups->groups.size(), 1u);
  EXPECT_EQ(groups->groups[0], (std::vector<int>{0, 1, 2, 3}));
  ASSERT_EQ(groups->corners.size(), 4u);
  std::array<int, 4> hits{};
  for (const Corner& c : groups->corners) {
    for (int k = 0; k < 4; ++k) {
      if ((c.position.cast<double>() - corners[k]).norm() < 0.005) ++hits[k];
    }
    // Only neighbouring sides meet.
    EXPECT_EQ((c.segment_b - c.segment_a + 4) % 2, 1);
  }
  EXPECT_EQ(hits, (std::array<int, 4>{1, 1, 1, 1}));
}

TEST(ClubSegmentsTest, EmptyInputGivesNothing) {
  const absl::StatusOr<SegmentGroups> groups = ClubSegments({}, ClubbingOptions{});
  ASSERT_TRUE(groups.ok());
  EXPECT_TRUE(groups->groups.empty());
  EXPECT_TRUE(groups->corners.empty());
}

TEST(ClubbingOptionsTest, InvalidOptionsAreRefused) {
  EXPECT_TRUE(ClubbingOptions{}.Validate().ok());
  ClubbingOptions o;
  o.perpendicular_tolerance_deg = -1.0;
  EXPECT_EQ(ClubSegments({}, o).status().code(), absl::StatusCode::kInvalidArgument);
  o = ClubbingOptions{};
  o.meet_distance_m = 0.0;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = ClubbingOptions{};
  o.end_gap_m = 2.0;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cornerpose
