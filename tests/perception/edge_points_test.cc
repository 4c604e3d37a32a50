#include "common/perception/edge_points.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <unordered_set>
#include <vector>

#include "common/perception/internal/round_half_away.h"
#include "common/perception/internal/select_kth.h"
#include "tests/support/scene_generator.h"
#include "tests/support/scene_kinds.h"
#include "tests/support/sensor_options.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
constexpr double kRadius = 0.02;

NoiseOptions NoNoise() {
  NoiseOptions noise;
  noise.enabled = false;
  return noise;
}

// n points uniformly distributed over a disc of radius r in the plane spanned
// by unit vectors a and b around the origin; keep(x, y) selects a part of it.
template <typename Keep>
std::vector<Eigen::Vector3f> SampleDisc(int n, double r, const Eigen::Vector3f& a,
                                        const Eigen::Vector3f& b, std::mt19937& rng, Keep keep) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3f> pts;
  while (static_cast<int>(pts.size()) < n) {
    const double rho = r * std::sqrt(unit(rng));
    const double phi = 2.0 * std::numbers::pi * unit(rng);
    const double x = rho * std::cos(phi), y = rho * std::sin(phi);
    if (!keep(x, y)) continue;
    pts.push_back(static_cast<float>(x) * a + static_cast<float>(y) * b);
  }
  return pts;
}

TEST(EdgeScoreTest, FlatDiscScoresNearZero) {
  std::mt19937 rng(1);
  const auto disc = SampleDisc(4000, kRadius, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY(),
                               rng, [](double, double) { return true; });
  EXPECT_LT(EdgeScore(Eigen::Vector3f::Zero(), disc), 0.05f);
  // A regular grid is symmetric about its centre: exactly 0 up to rounding.
  std::vector<Eigen::Vector3f> grid;
  for (int i = -10; i <= 10; ++i) {
    for (int j = -10; j <= 10; ++j) {
      if (i * i + j * j <= 100) grid.emplace_back(0.002f * i, 0.002f * j, 0.0f);
    }
  }
  EXPECT_LT(EdgeScore(Eigen::Vector3f::Zero(), grid), 1e-5f);
}

TEST(EdgeScoreTest, HalfDiscScoresTwoOverPi) {
  std::mt19937 rng(2);
  // The directions of a uniform half disc are uniform over a half circle:
  // |mean| = (1/pi) integral of cos over [-pi/2, pi/2] = 2/pi.
  const auto half = SampleDisc(4000, kRadius, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY(),
                               rng, [](double, double y) { return y > 0.0; });
  EXPECT_NEAR(EdgeScore(Eigen::Vector3f::Zero(), half), 2.0 / std::numbers::pi, 0.05);
}

TEST(EdgeScoreTest, RightAngleCreaseScoresPointFourFive) {
  std::mt19937 rng(3);
  // Two half discs of equal density sharing the crease along x, one in the
  // x-y plane (y > 0), one in the x-z plane (z > 0). Each contributes 2/pi
  // along its own in-plane normal, so |mean| = (2/pi) |y + z| / 2 =
  // sqrt(2)/pi = 0.450.
  const Eigen::Vector3f x = Eigen::Vector3f::UnitX();
  auto a = SampleDisc(3000, kRadius, x, Eigen::Vector3f::UnitY(), rng,
                      [](double, double y) { return y > 0.0; });
  const auto b = SampleDisc(3000, kRadius, x, Eigen::Vector3f::UnitZ(), rng,
                            [](double, double y) { return y > 0.0; });
  a.insert(a.end(), b.begin(), b.end());
  const float score = EdgeScore(Eigen::Vector3f::Zero(), a);
  std::cout << "crease score " << score << "\n";
  EXPECT_NEAR(score, std::sqrt(2.0) / std::numbers::pi, 0.03);
  EXPECT_NEAR(score, 0.45, 0.06);
  // The paper's threshold t_h = 0.35 separates all three cases.
  EXPECT_GT(score, EdgePointOptions{}.threshold);
}

TEST(EdgeScoreTest, IgnoresCopiesOfThePointAndEmptySets) {
  EXPECT_EQ(EdgeScore(Eigen::Vector3f(1, 2, 3), {}), 0.0f);
  EXPECT_EQ(EdgeScore(Eigen::Vector3f(1, 2, 3), {Eigen::Vector3f(1, 2, 3)}), 0.0f);
  // One real neighbour: a single unit vector, score 1; the copy is not counted.
  EXPECT_NEAR(EdgeScore(Eigen::Vector3f::Zero(), {Eigen::Vector3f::Zero(), {0.01f, 0, 0}}), 1.0f,
              1e-6f);
}

// One carton_s lying on the floor below a camera 1.2 m away.
Scene SingleBoxScene(double tilt_deg, double camera_yaw_deg, double box_yaw_deg) {
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.2, tilt_deg, camera_yaw_deg, 0.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() =
      Eigen::AngleAxisd(box_yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  pose.translation() = Eigen::Vector3d(0.0, 0.0, 0.5 * kCartonS.h);
  scene.boxes.push_back({kCartonS, pose, true});
  return scene;
}

// Where an edge point lies relative to the box, in the box frame.
struct BoxFrameClassifier {
  Eigen::Isometry3d box_T_camera;
  BoxDims dims;

  Eigen::Vector3d Local(const Eigen::Vector3f& p) const { return box_T_camera * p.cast<double>(); }
  bool InTopInterior(const Eigen::Vector3f& p, double margin) const {
    const Eigen::Vector3d q = Local(p);
    return std::abs(q.z() - 0.5 * dims.h) < 0.005 && std::abs(q.x()) < 0.5 * dims.l - margin &&
           std::abs(q.y()) < 0.5 * dims.b - margin;
  }
  // On the floor (box frame z = -h/2) and farther than `margin` from the footprint.
  bool OnFloorFarFromBox(const Eigen::Vector3f& p, double margin) const {
    const Eigen::Vector3d q = Local(p);
    return std::abs(q.z() + 0.5 * dims.h) < 0.005 &&
           (std::abs(q.x()) > 0.5 * dims.l + margin || std::abs(q.y()) > 0.5 * dims.b + margin);
  }
};

// Samples the top outline every 1 cm, in the camera frame.
std::vector<Eigen::Vector3f> TopOutline(const Eigen::Isometry3d& camera_T_box, const BoxDims& d) {
  std::vector<Eigen::Vector3f> out;
  const double hl = 0.5 * d.l, hb = 0.5 * d.b, z = 0.5 * d.h;
  for (double x = -hl; x <= hl + 1e-9; x += 0.01) {
    out.push_back((camera_T_box * Eigen::Vector3d(x, -hb, z)).cast<float>());
    out.push_back((camera_T_box * Eigen::Vector3d(x, hb, z)).cast<float>());
  }
  for (double y = -hb; y <= hb + 1e-9; y += 0.01) {
    out.push_back((camera_T_box * Eigen::Vector3d(-hl, y, z)).cast<float>());
    out.push_back((camera_T_box * Eigen::Vector3d(hl, y, z)).cast<float>());
  }
  return out;
}

// Share of the outline samples with an edge point within `reach`.
double OutlineCoverage(const std::vector<Eigen::Vector3f>& outline,
                       const std::vector<Eigen::Vector3f>& edges, double reach) {
  int covered = 0;
  for (const Eigen::Vector3f& s : outline) {
    for (const Eigen::Vector3f& e : edges) {
      if ((e - s).norm() < reach) {
        ++covered;
        break;
      }
    }
  }
  return outline.empty() ? 0.0 : static_cast<double>(covered) / outline.size();
}

struct ViewParam {
  double tilt_deg;
  double camera_yaw_deg;
  double box_yaw_deg;
};

// "tilt25_camyaw40_boxyawm20": names the ctest test (gtest_discover_tests
// puts the printed parameter in place of the gtest index).
std::string ViewName(const ViewParam& v) {
  std::string name = "tilt" + std::to_string(std::lround(v.tilt_deg)) + "_camyaw" +
                     std::to_string(std::lround(v.camera_yaw_deg)) + "_boxyaw" +
                     std::to_string(std::lround(v.box_yaw_deg));
  std::replace(name.begin(), name.end(), '-', 'm');
  return name;
}
void PrintTo(const ViewParam& v, std::ostream* os) { *os << ViewName(v); }

class EdgePointsOnRenderedBoxTest : public ::testing::TestWithParam<ViewParam> {};

TEST_P(EdgePointsOnRenderedBoxTest, OrganizedFindsTheTopOutlineOnly) {
  const ViewParam view = GetParam();
  const RenderedScene out =
      Render(SingleBoxScene(view.tilt_deg, view.camera_yaw_deg, view.box_yaw_deg), NoNoise());
  ASSERT_TRUE(out.cloud.organized());
  const GroundTruthBox& gt = out.boxes.at(0);
  const absl::StatusOr<EdgePoints> edges =
      DetectEdgePoints(out.cloud, EdgePointOptions{}, out.camera.fx);
  ASSERT_TRUE(edges.ok()) << edges.status();
  ASSERT_FALSE(edges->points.empty());
  ASSERT_EQ(edges->points.size(), edges->indices.size());
  ASSERT_EQ(edges->points.size(), edges->scores.size());
  for (size_t i = 0; i < edges->points.size(); ++i) {
    EXPECT_EQ(edges->points[i], out.cloud.xyz[edges->indices[i]]);
    EXPECT_GT(edges->scores[i], EdgePointOptions{}.threshold);
  }

  const BoxFrameClassifier where{gt.camera_T_box.inverse(), kCartonS};
  // The regions checked below hold many points of the cloud.
  int cloud_top_interior = 0, cloud_far_floor = 0;
  for (const Eigen::Vector3f& p : out.cloud.xyz) {
    if (!PointCloud::IsValid(p)) continue;
    cloud_top_interior += where.InTopInterior(p, 0.03);
    cloud_far_floor += where.OnFloorFarFromBox(p, 0.05);
  }
  ASSERT_GT(cloud_top_interior, 2000);
  ASSERT_GT(cloud_far_floor, 100000);
  int top_interior = 0, far_floor = 0;
  for (const Eigen::Vector3f& p : edges->points) {
    top_interior += where.InTopInterior(p, 0.03);
    far_floor += where.OnFloorFarFromBox(p, 0.05);
  }
  EXPECT_EQ(top_interior, 0);
  EXPECT_EQ(far_floor, 0);
  const double coverage =
      OutlineCoverage(TopOutline(gt.camera_T_box, kCartonS), edges->points, 0.01);
  std::cout << edges->points.size() << " edge points, outline coverage " << coverage << "\n";
  EXPECT_GE(coverage, 0.97);
}

TEST_P(EdgePointsOnRenderedBoxTest, UnorganizedFindsTheTopOutline) {
  const ViewParam view = GetParam();
  const RenderedScene out =
      Render(SingleBoxScene(view.tilt_deg, view.camera_yaw_deg, view.box_yaw_deg), NoNoise());
  const GroundTruthBox& gt = out.boxes.at(0);
  // Only the part of the frame around the box: the unorganized path has no
  // image border to stop at, so the cloud's own rim scores as a boundary.
  PointCloud cloud;
  const Eigen::Isometry3d box_T_camera = gt.camera_T_box.inverse();
  for (const Eigen::Vector3f& p : out.cloud.xyz) {
    if (!PointCloud::IsValid(p)) continue;
    const Eigen::Vector3d q = box_T_camera * p.cast<double>();
    if (std::abs(q.x()) < 0.5 * kCartonS.l + 0.15 && std::abs(q.y()) < 0.5 * kCartonS.b + 0.15) {
      cloud.xyz.push_back(p);
    }
  }
  std::mt19937 rng(7);
  std::shuffle(cloud.xyz.begin(), cloud.xyz.end(), rng);
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  ASSERT_FALSE(cloud.organized());

  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{});
  ASSERT_TRUE(edges.ok()) << edges.status();
  const BoxFrameClassifier where{box_T_camera, kCartonS};
  int top_interior = 0;
  for (size_t i = 0; i < edges->points.size(); ++i) {
    EXPECT_EQ(edges->points[i], cloud.xyz[edges->indices[i]]);
    top_interior += where.InTopInterior(edges->points[i], 0.03);
  }
  EXPECT_EQ(top_interior, 0);
  const double coverage =
      OutlineCoverage(TopOutline(gt.camera_T_box, kCartonS), edges->points, 0.01);
  std::cout << edges->points.size() << " edge points, outline coverage " << coverage << "\n";
  EXPECT_GE(coverage, 0.97);
}

INSTANTIATE_TEST_SUITE_P(Views, EdgePointsOnRenderedBoxTest,
                         ::testing::Values(ViewParam{0.0, 0.0, 0.0}, ViewParam{0.0, 0.0, 30.0},
                                           ViewParam{25.0, 40.0, -20.0}));

// The cells next to a coarse hit whose own centre scores low can be left
// unscored (EdgePointOptions::coarse_skip_factor, off by default): on clutter
// of every kind and both sensor models that loses under 1 % of the edge
// points (only ever loses: the scores themselves do not change). Off by
// default all the same: on the stereo sets that 1 % changed which boxes were
// found (scripts/evaluate, README "Speed").
TEST(EdgePointsTest, SkippingLowCellsNextToHitsKeepsTheEdgePoints) {
  size_t all = 0, lost = 0;
  for (const SensorKind sensor_kind : {SensorKind::kKinect, SensorKind::kStereo}) {
    for (const char* kind : {"heap", "pallet", "touching"}) {
      for (int i = 0; i < 2; ++i) {
        SensorOptions sensor;
        sensor.kind = sensor_kind;
        const CameraIntrinsics k = *SensorIntrinsics(sensor_kind, 640, 480);
        std::string type;
        const absl::StatusOr<Scene> scene = MakeSceneOfKind(kind, kCartonS, i, 500 + 10 * i,
                                                            SensorPlacement(sensor_kind, k), &type);
        ASSERT_TRUE(scene.ok()) << scene.status();
        const RenderedScene out = Render(*scene, sensor);
        EdgePointOptions every_cell;
        every_cell.coarse_skip_factor = 0.0;
        const absl::StatusOr<EdgePoints> a = DetectEdgePoints(out.cloud, every_cell, out.camera.fx);
        EdgePointOptions skipping;
        skipping.coarse_skip_factor = 0.5;
        const absl::StatusOr<EdgePoints> b = DetectEdgePoints(out.cloud, skipping, out.camera.fx);
        ASSERT_TRUE(a.ok() && b.ok());
        const std::unordered_set<int> in_b(b->indices.begin(), b->indices.end());
        size_t lost_here = 0;
        for (int idx : a->indices) lost_here += in_b.count(idx) == 0;
        EXPECT_LE(b->indices.size(), a->indices.size());
        all += a->indices.size();
        lost += lost_here;
      }
    }
  }
  const double share = static_cast<double>(lost) / static_cast<double>(all);
  std::cout << "skipping low cells: " << lost << " of " << all << " edge points lost ("
            << 100.0 * share << " %)\n";
  ASSERT_GT(all, 10000u);
  EXPECT_LE(share, 0.01);
}

// SelectKth gives what std::nth_element puts at k, on every size the edge
// score sees, with ties (quantized depths) and with values all alike.
TEST(SelectKthTest, MatchesNthElement) {
  std::mt19937 rng(3);
  for (int n = 1; n <= 130; ++n) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<float> a(n);
      const int levels = trial % 3 == 0 ? 1 : trial % 3 == 1 ? 4 : 1000;
      std::uniform_int_distribution<int> level(0, levels - 1);
      for (float& x : a) x = 0.001f * static_cast<float>(level(rng)) - 0.2f;
      for (const int k : {0, n / 2, n - 1}) {
        std::vector<float> b = a, c = a, scratch(n);
        std::nth_element(b.begin(), b.begin() + k, b.end());
        ASSERT_EQ(internal::SelectKth(c.data(), n, k, scratch.data()), b[k])
            << "n " << n << " k " << k;
      }
    }
  }
}

TEST(EdgePointsTest, CoarsePassKeepsNearlyAllFullResolutionEdges) {
  const RenderedScene out = Render(MakeHeapScene(kCartonS, 10, 5), NoiseOptions{});
  EdgePointOptions fine;
  fine.coarse_step = 1;
  EdgePointOptions coarse;
  coarse.coarse_step = 3;
  const absl::StatusOr<EdgePoints> a = DetectEdgePoints(out.cloud, fine, out.camera.fx);
  const absl::StatusOr<EdgePoints> b = DetectEdgePoints(out.cloud, coarse, out.camera.fx);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_GT(a->indices.size(), 1000u);
  const std::unordered_set<int> in_a(a->indices.begin(), a->indices.end());
  const std::unordered_set<int> in_b(b->indices.begin(), b->indices.end());
  int common = 0;
  for (int i : b->indices) common += in_a.count(i) > 0;
  const double jaccard = static_cast<double>(common) / (in_a.size() + in_b.size() - common);
  std::cout << "coarse_step 1: " << in_a.size() << " edge points, 3: " << in_b.size()
            << ", overlap " << jaccard << "\n";
  EXPECT_GE(jaccard, 0.98);
}

TEST(EdgePointsTest, SameResultWithOneOrManyThreads) {
  const RenderedScene out = Render(MakeHeapScene(kCartonS, 6, 9), NoiseOptions{});
  EdgePointOptions one;
  one.num_threads = 1;
  EdgePointOptions four;
  four.num_threads = 4;
  const absl::StatusOr<EdgePoints> a = DetectEdgePoints(out.cloud, one, out.camera.fx);
  const absl::StatusOr<EdgePoints> b = DetectEdgePoints(out.cloud, four, out.camera.fx);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_FALSE(a->indices.empty());
  EXPECT_EQ(a->indices, b->indices);
  EXPECT_EQ(a->scores, b->scores);
}

TEST(EdgePointOptionsTest, ValidateRejectsOutOfRangeValues) {
  EXPECT_TRUE(EdgePointOptions{}.Validate().ok());
  auto with = [](auto set) {
    EdgePointOptions o;
    set(o);
    return o.Validate();
  };
  EXPECT_EQ(with([](EdgePointOptions& o) { o.radius_m = 0.0; }).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](EdgePointOptions& o) { o.radius_m = 5.0; }).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](EdgePointOptions& o) { o.radius_m = std::nan(""); }).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](EdgePointOptions& o) { o.threshold = 1.5; }).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](EdgePointOptions& o) { o.num_threads = 0; }).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](EdgePointOptions& o) { o.coarse_step = 0; }).code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(EdgePointsTest, BadOptionsAreRefusedBeforeAnyWork) {
  PointCloud cloud;
  cloud.width = 3;
  cloud.height = 1;
  cloud.xyz = {{0, 0, 1}, {0.01f, 0, 1}, {0, 0.01f, 1}};
  EdgePointOptions o;
  o.threshold = 1.5;
  EXPECT_EQ(DetectEdgePoints(cloud, o).status().code(), absl::StatusCode::kInvalidArgument);
  o = EdgePointOptions{};
  o.radius_m = 0.0;
  EXPECT_EQ(DetectEdgePoints(cloud, o).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(EdgePointsTest, AllNanOrganizedFrameHasNoEdgePoints) {
  PointCloud cloud;
  cloud.width = 640;
  cloud.height = 480;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.xyz.assign(640 * 480, Eigen::Vector3f(nan, nan, nan));
  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{}, 525.0);
  ASSERT_TRUE(edges.ok()) << edges.status();
  EXPECT_TRUE(edges->points.empty());
  EXPECT_TRUE(edges->indices.empty());
}

TEST(EdgePointsTest, EmptyCloudHasNoEdgePoints) {
  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(PointCloud{}, EdgePointOptions{});
  ASSERT_TRUE(edges.ok()) << edges.status();
  EXPECT_TRUE(edges->points.empty());
}

TEST(EdgePointsTest, SizeMismatchIsInvalidArgument) {
  PointCloud cloud;
  cloud.width = 10;
  cloud.height = 10;
  cloud.xyz.assign(99, Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(DetectEdgePoints(cloud, EdgePointOptions{}).status().code(),
            absl::StatusCode::kInvalidArgument);
  cloud.width = 100;
  cloud.height = 1;
  EXPECT_EQ(DetectEdgePoints(cloud, EdgePointOptions{}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(EdgePointsTest, OrganizedFrameNeedsAFocalLength) {
  const RenderedScene out = Render(SingleBoxScene(0.0, 0.0, 0.0), NoNoise());
  EXPECT_EQ(DetectEdgePoints(out.cloud, EdgePointOptions{}, 0.0).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(DetectEdgePoints(out.cloud, EdgePointOptions{}, std::numeric_limits<double>::infinity())
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

// The pixel loops' inlined rounding gives what std::lround gives: at and
// beside every half, and on random values, floats and doubles.
TEST(RoundHalfAwayTest, MatchesLround) {
  for (int q = -8000; q <= 8000; ++q) {
    const float f = 0.25f * static_cast<float>(q);
    for (const float x : {f, std::nextafter(f, -1e9f), std::nextafter(f, 1e9f)}) {
      ASSERT_EQ(internal::RoundHalfAway(x), std::lround(x)) << x;
    }
    const double d = 0.25 * q;
    for (const double x : {d, std::nextafter(d, -1e9), std::nextafter(d, 1e9)}) {
      ASSERT_EQ(internal::RoundHalfAway(x), std::lround(x)) << x;
    }
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> any(-1e6, 1e6);
  for (int i = 0; i < 100000; ++i) {
    const double d = any(rng);
    ASSERT_EQ(internal::RoundHalfAway(d), std::lround(d)) << d;
    const float f = static_cast<float>(d / 200.0);
    ASSERT_EQ(internal::RoundHalfAway(f), std::lround(f)) << f;
  }
}

}  // namespace
}  // namespace cornerpose::testing
