#include "common/perception/box_pose.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "common/perception/pose_error.h"

namespace cornerpose {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
constexpr BoxDims kBrick{0.19, 0.09, 0.057};
constexpr double kDeg = std::numbers::pi / 180.0;

bool Contains(const std::vector<AxisAssignment>& list, int axis1, int axis2) {
  return std::any_of(list.begin(), list.end(),
                     [&](const AxisAssignment& a) { return a.axis1 == axis1 && a.axis2 == axis2; });
}

TEST(MatchEdgeLengthsTest, ExactLengthsComeFirst) {
  const PoseOptions options;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      const std::vector<AxisAssignment> list =
          MatchEdgeLengths(kCartonS[i], kCartonS[j], kCartonS, options);
      ASSERT_FALSE(list.empty());
      EXPECT_EQ(list[0].axis1, i);
      EXPECT_EQ(list[0].axis2, j);
      EXPECT_NEAR(list[0].length_cost, 0.0, 1e-9);
      for (size_t k = 1; k < list.size(); ++k) {
        EXPECT_GE(list[k].length_cost, list[k - 1].length_cost);  // cheapest first
        EXPECT_GT(list[k].length_cost, 0.1);
      }
    }
  }
}

TEST(MatchEdgeLengthsTest, NearlyExactLengthsStillComeFirst) {
  // 1 cm off, within length_tolerance_m.
  const std::vector<AxisAssignment> list = MatchEdgeLengths(0.29, 0.21, kCartonS, PoseOptions{});
  ASSERT_FALSE(list.empty());
  EXPECT_EQ(list[0].axis1, 0);
  EXPECT_EQ(list[0].axis2, 1);
  EXPECT_GT(list[0].length_cost, 0.0);
  EXPECT_LT(list[0].length_cost, 1.0);
}

TEST(MatchEdgeLengthsTest, AnOccludedEdgeIsStillAllowed) {
  // The l edge is partly hidden: 0.24 of 0.30, more than 2.5 cm short.
  const std::vector<AxisAssignment> list = MatchEdgeLengths(0.24, 0.20, kCartonS, PoseOptions{});
  ASSERT_FALSE(list.empty());
  EXPECT_TRUE(Contains(list, 0, 1));
  EXPECT_EQ(list[0].axis1, 0);
  EXPECT_EQ(list[0].axis2, 1);
  // ... but costs more than an exact match.
  EXPECT_GE(list[0].length_cost, 1.0);
}

TEST(MatchEdgeLengthsTest, TooShortForASideRulesItOut) {
  // 0.08 is below min_occluded_fraction (0.3) of l = 0.30 (0.09) but not of b or h.
  const std::vector<AxisAssignment> list = MatchEdgeLengths(0.08, 0.20, kCartonS, PoseOptions{});
  EXPECT_FALSE(Contains(list, 0, 1));
  EXPECT_TRUE(Contains(list, 2, 1));
  for (const AxisAssignment& a : list) EXPECT_NE(a.axis1, a.axis2);
}

TEST(MatchEdgeLengthsTest, RunOnEdgesNeedAllowRunOn) {
  PoseOptions options;
  // 0.45 is longer than every side: it can only be a side running on.
  EXPECT_TRUE(Contains(MatchEdgeLengths(0.45, 0.20, kCartonS, options), 0, 1));
  options.allow_run_on = false;
  EXPECT_TRUE(MatchEdgeLengths(0.45, 0.20, kCartonS, options).empty());
}

TEST(CheapestReadingsTest, KeepsTheCheapestAndTheirTies) {
  // Two edges running on past every side: all six readings, the cheapest
  // reads them as the two longest sides.
  const std::vector<AxisAssignment> all = MatchEdgeLengths(0.45, 0.40, kCartonS, PoseOptions{});
  ASSERT_EQ(all.size(), 6u);
  const std::vector<AxisAssignment> three = CheapestReadings(all, 3);
  ASSERT_EQ(three.size(), 3u);
  for (size_t k = 0; k < three.size(); ++k) {
    EXPECT_EQ(three[k].axis1, all[k].axis1);
    EXPECT_EQ(three[k].axis2, all[k].axis2);
  }
  EXPECT_EQ(three[0].axis1, 0);
  EXPECT_EQ(three[0].axis2, 1);
  EXPECT_EQ(CheapestReadings(all, 0).size(), 6u);  // 0: every reading
  EXPECT_EQ(CheapestReadings(all, 8).size(), 6u);
  // A square box's l and b cost the same read either way: a tie with the
  // last kept stays, whatever order the axes were tried in.
  constexpr BoxDims kSquare{0.30, 0.30, 0.20};
  const std::vector<AxisAssignment> square = MatchEdgeLengths(0.30, 0.20, kSquare, PoseOptions{});
  ASSERT_GE(square.size(), 2u);
  ASSERT_NEAR(square[0].length_cost, square[1].length_cost, 1e-12);
  EXPECT_EQ(CheapestReadings(square, 1).size(), 2u);
}

TEST(CheapestReadingsTest, ANegativeCountIsRejectedByName) {
  PoseOptions o;
  o.max_readings_per_corner = -1;
  const absl::Status s = o.Validate();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(std::string(s.message()).find("max_readings_per_corner"), std::string::npos);
}

// The outward normal of `face` of a box at camera_T_box faces the camera.
bool FaceSeesCamera(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims, int axis,
                    double sign) {
  const Eigen::Vector3d n = sign * camera_T_box.linear().col(axis);
  const Eigen::Vector3d centre = camera_T_box.translation() + n * dims[axis] / 2.0;
  return n.dot(-centre) > 1e-3 * centre.norm();
}

Eigen::Isometry3d MakePose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = R;
  pose.translation() = t;
  return pose;
}

// Box poses in front of the camera: lying flat seen from above, turned,
// tilted and seen obliquely, and on their sides.
std::vector<Eigen::Isometry3d> TestPoses() {
  // Camera looking straight down at the floor: box z (up) is camera -z.
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  std::vector<Eigen::Isometry3d> poses;
  poses.push_back(MakePose(down, {0.0, 0.0, 1.1}));
  poses.push_back(MakePose(down * Eigen::AngleAxisd(35 * kDeg, Eigen::Vector3d::UnitZ()).matrix(),
                           {0.15, -0.1, 1.2}));
  // Tilted boxes: three faces in view.
  poses.push_back(MakePose(Eigen::AngleAxisd(25 * kDeg, Eigen::Vector3d::UnitX()) * down *
                               Eigen::AngleAxisd(40 * kDeg, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitY()),
                           {-0.2, 0.1, 1.0}));
  poses.push_back(MakePose((Eigen::AngleAxisd(-0.6, Eigen::Vector3d(1, 2, 0.5).normalized()) *
                            Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ()))
                                   .matrix() *
                               down,
                           {0.1, 0.2, 1.4}));
  // On its side (l-h face up), seen at a tilt.
  poses.push_back(MakePose(Eigen::AngleAxisd(-20 * kDeg, Eigen::Vector3d::UnitX()) * down *
                               Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(15 * kDeg, Eigen::Vector3d::UnitY()),
                           {0.05, 0.0, 1.3}));
  // Standing on its end (b-h face up), far to the side of the image.
  poses.push_back(MakePose(Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitY()).matrix() *
                               Eigen::AngleAxisd(10 * kDeg, Eigen::Vector3d::UnitZ()).matrix(),
                           {-0.4, 0.05, 1.2}));
  return poses;
}

// For every face of the box that looks at the camera, every one of its four
// corners and both orders of its two edges: PoseFromCorner recovers the
// pose up to the box's symmetries, with the third axis toward the camera.
void CheckAllCorners(const Eigen::Isometry3d& truth, const BoxDims& dims,
                     std::array<int, 3>* pairs_seen) {
  const Eigen::Matrix3d R = truth.linear();
  for (int k = 0; k < 3; ++k) {
    for (double sk : {1.0, -1.0}) {
      if (!FaceSeesCamera(truth, dims, k, sk)) continue;
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      ++(*pairs_seen)[k];
      for (double si : {1.0, -1.0}) {
        for (double sj : {1.0, -1.0}) {
          Eigen::Vector3d local;
          local[i] = si * dims[i] / 2;
          local[j] = sj * dims[j] / 2;
          local[k] = sk * dims[k] / 2;
          const Eigen::Vector3d p1 = truth * local;
          // The two edges run from the corner into the face: toward -si along
          // axis i, -sj along axis j, as long as the sides (eq. 4 uses the
          // far extremities p2, p3; their distance is irrelevant).
          const Eigen::Vector3d e1 = -si * dims[i] * R.col(i);
          const Eigen::Vector3d e2 = -sj * dims[j] * R.col(j);
          for (bool swap : {false, true}) {
            SCOPED_TRACE(::testing::Message() << "face axis " << k << " sign " << sk << ", corner "
                                              << si << "," << sj << ", swap " << swap);
            const AxisAssignment as{swap ? j : i, swap ? i : j, 0.0};
            const Eigen::Isometry3d pose =
                PoseFromCorner(p1, swap ? e2 : e1, swap ? e1 : e2, as, dims);
            const PoseError err = ComparePoses(pose, truth, dims);
            EXPECT_LT(err.translation_m, 1e-6);
            EXPECT_LT(err.rotation_deg, 1e-4);
            EXPECT_NEAR(pose.linear().determinant(), 1.0, 1e-9);
            // The third axis (k) faces the camera (eq. 5: d . t > 0).
            EXPECT_GT(pose.linear().col(k).dot(-p1.normalized()), 0.0);
          }
        }
      }
    }
  }
}

TEST(PoseFromCornerTest, RecoversThePoseFromEveryVisibleCornerAndEdgeOrder) {
  for (const BoxDims& dims : {kCartonS, kBrick}) {
    std::array<int, 3> pairs_seen{};  // by the face's normal axis: b/h, l/h, l/b edges
    int n = 0;
    for (const Eigen::Isometry3d& truth : TestPoses()) {
      SCOPED_TRACE(::testing::Message() << "pose " << n++ << " dims " << dims.l);
      CheckAllCorners(truth, dims, &pairs_seen);
    }
    // The poses cover all three kinds of edge pair.
    EXPECT_GE(pairs_seen[0], 2);  // b/h edges (an x face)
    EXPECT_GE(pairs_seen[1], 2);  // l/h edges (a y face)
    EXPECT_GE(pairs_seen[2], 2);  // l/b edges (a z face)
  }
}

TEST(PoseFromCornerTest, RandomPosesAndCorners) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<int, 3> pairs_seen{};
  for (int n = 0; n < 50; ++n) {
    const Eigen::Quaterniond q(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized());
    const Eigen::Isometry3d truth =
        MakePose(q.toRotationMatrix(), {0.4 * u(rng), 0.3 * u(rng), 1.2 + 0.3 * u(rng)});
    SCOPED_TRACE(n);
    CheckAllCorners(truth, kCartonS, &pairs_seen);
  }
  EXPECT_GT(pairs_seen[0] + pairs_seen[1] + pairs_seen[2], 100);
}

TEST(PoseFromCornerTest, SecondEdgeIsOrthogonalisedAgainstTheFirst) {
  const Eigen::Isometry3d truth = TestPoses()[2];
  const Eigen::Matrix3d R = truth.linear();
  const Eigen::Vector3d p1 = truth * Eigen::Vector3d(-0.15, -0.10, 0.075);
  // Not quite perpendicular: d2 leans 3 degrees toward d1.
  const Eigen::Vector3d d1 = R.col(0);
  const Eigen::Vector3d d2 = R.col(1) + std::tan(3 * kDeg) * R.col(0);
  ASSERT_TRUE(FaceSeesCamera(truth, kCartonS, 2, 1.0));
  const Eigen::Isometry3d pose = PoseFromCorner(p1, 0.3 * d1, 0.2 * d2, {0, 1, 0.0}, kCartonS);
  const PoseError err = ComparePoses(pose, truth, kCartonS);
  EXPECT_LT(err.translation_m, 1e-6);
  EXPECT_LT(err.rotation_deg, 1e-4);
}

TEST(PoseFromCornerTest, WrongAssignmentGivesAWrongPose) {
  // The l/b corner read as l/h: the pose is a different box, far off.
  const Eigen::Isometry3d truth = TestPoses()[0];
  const Eigen::Matrix3d R = truth.linear();
  const Eigen::Vector3d p1 = truth * Eigen::Vector3d(-0.15, -0.10, 0.075);
  const Eigen::Isometry3d pose = PoseFromCorner(p1, R.col(0), R.col(1), {0, 2, 0.0}, kCartonS);
  const PoseError err = ComparePoses(pose, truth, kCartonS);
  EXPECT_GT(err.rotation_deg, 45.0);
}

TEST(BoxCornersTest, CornersAreTheBoxVertices) {
  const Eigen::Isometry3d pose = TestPoses()[3];
  const std::array<Eigen::Vector3d, 8> corners = BoxCorners(pose, kCartonS);
  const Eigen::Isometry3d inv = pose.inverse();
  for (const Eigen::Vector3d& c : corners) {
    const Eigen::Vector3d local = inv * c;
    EXPECT_NEAR(std::abs(local.x()), 0.15, 1e-12);
    EXPECT_NEAR(std::abs(local.y()), 0.10, 1e-12);
    EXPECT_NEAR(std::abs(local.z()), 0.075, 1e-12);
  }
  for (int a = 0; a < 8; ++a) {
    for (int b = a + 1; b < 8; ++b) EXPECT_GT((corners[a] - corners[b]).norm(), 0.1);
  }
}

// The four corners of the top (+z) face.
std::vector<Eigen::Vector3d> TopCorners(const Eigen::Isometry3d& pose, const BoxDims& d) {
  std::vector<Eigen::Vector3d> out;
  for (double sx : {-1.0, 1.0}) {
    for (double sy : {-1.0, 1.0})
      out.push_back(pose * Eigen::Vector3d(sx * d.l / 2, sy * d.b / 2, d.h / 2));
  }
  return out;
}

Eigen::Isometry3d Perturbed(const Eigen::Isometry3d& pose) {
  Eigen::Isometry3d out = pose;
  out.translation() += Eigen::Vector3d(0.006, -0.005, 0.006);  // ~1 cm
  out.linear() =
      out.linear() * Eigen::AngleAxisd(1.0 * kDeg, Eigen::Vector3d(1, 1, 1).normalized()).matrix();
  return out;
}

TEST(RefineWithCornersTest, FourExactCornersPullThePoseBack) {
  for (const Eigen::Isometry3d& truth : TestPoses()) {
    Eigen::Isometry3d pose = Perturbed(truth);
    ASSERT_GT(ComparePoses(pose, truth, kCartonS).translation_m, 0.009);
    const int used = RefineWithCorners(TopCorners(truth, kCartonS), kCartonS, PoseOptions{}, &pose);
    EXPECT_EQ(used, 4);
    const PoseError err = ComparePoses(pose, truth, kCartonS);
    EXPECT_LT(err.translation_m, 0.001);
    EXPECT_LT(err.rotation_deg, 0.1);
  }
}

TEST(RefineWithCornersTest, NoisyCornersStillHelp) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  const Eigen::Isometry3d truth = TestPoses()[2];
  std::vector<Eigen::Vector3d> corners;
  for (const Eigen::Vector3d& c : BoxCorners(truth, kCartonS)) {
    corners.push_back(c + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  Eigen::Isometry3d pose = Perturbed(truth);
  const double before = ComparePoses(pose, truth, kCartonS).translation_m;
  EXPECT_EQ(RefineWithCorners(corners, kCartonS, PoseOptions{}, &pose), 8);
  const double after = ComparePoses(pose, truth, kCartonS).translation_m;
  EXPECT_LT(after, 0.003);
  EXPECT_LT(after, 0.5 * before);
}

TEST(RefineWithCornersTest, TwoCornersLeaveThePoseUnchanged) {
  const Eigen::Isometry3d truth = TestPoses()[1];
  const Eigen::Isometry3d start = Perturbed(truth);
  Eigen::Isometry3d pose = start;
  std::vector<Eigen::Vector3d> two = TopCorners(truth, kCartonS);
  two.resize(2);
  EXPECT_EQ(RefineWithCorners(two, kCartonS, PoseOptions{}, &pose), 0);
  EXPECT_TRUE(pose.isApprox(start, 1e-15));
}

TEST(RefineWithCornersTest, CornersFarFromThePoseAreNotMatched) {
  const Eigen::Isometry3d truth = TestPoses()[1];
  Eigen::Isometry3d pose = truth;
  pose.translation() += Eigen::Vector3d(0.05, 0.0, 0.0);  // beyond corner_match_m = 3 cm
  const Eigen::Isometry3d start = pose;
  EXPECT_EQ(RefineWithCorners(TopCorners(truth, kCartonS), kCartonS, PoseOptions{}, &pose), 0);
  EXPECT_TRUE(pose.isApprox(start, 1e-15));
}

TEST(PoseOptionsTest, InvalidOptionsAreRefused) {
  EXPECT_TRUE(PoseOptions{}.Validate().ok());
  PoseOptions o;
  o.length_tolerance_m = 0.0;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = PoseOptions{};
  o.min_occluded_fraction = 1.5;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = PoseOptions{};
  o.corner_match_m = -0.01;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cornerpose
