// Numeric inputs at the detector's boundary (issue 11): depths near zero,
// absurd focal lengths and piles of identical points must give a status or a
// bounded amount of work, never a crash or a stall.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "common/box/box_models.h"
#include "common/perception/detector.h"
#include "common/perception/edge_points.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

using ::testing::HasSubstr;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A flat wall at 1 m seen by a 160 x 120 camera (fx 130 px), with `near`
// pixels (spread over the interior) at z = 1e-9 m.
PointCloud WallWithNearPoints(int near) {
  const CameraIntrinsics k{160, 120, 130.0, 130.0, 79.5, 59.5};
  PointCloud cloud;
  cloud.width = k.width;
  cloud.height = k.height;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double z = 1.0;
      cloud.xyz.emplace_back((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z);
    }
  }
  for (int i = 0; i < near; ++i) {
    const int u = 70 + 3 * i, v = 55 + i;  // > 64 px from every border
    const float z = 1e-9f;
    cloud.xyz[v * k.width + u] = Eigen::Vector3f((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z);
  }
  return cloud;
}

// The SIGSEGV of issue 11: r fx / z = 2e7 px went through an int cast before
// it was clamped, and the neighbour table index became INT_MIN.
TEST(InputBoundsTest, EdgePointsSurviveDepthsNearZero) {
  const PointCloud cloud = WallWithNearPoints(5);
  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{}, 130.0);
  ASSERT_TRUE(edges.ok()) << edges.status();
  // A flat wall has no edges; the near points have no neighbours within r_s.
  EXPECT_TRUE(edges->points.empty());
}

TEST(InputBoundsTest, EdgePointsSurviveAnAbsurdFocalLength) {
  const PointCloud cloud = WallWithNearPoints(0);
  for (double focal : {1e12, 1e300}) {
    SCOPED_TRACE(focal);
    const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{}, focal);
    ASSERT_TRUE(edges.ok()) << edges.status();
    EXPECT_TRUE(edges->points.empty());
  }
}

TEST(InputBoundsTest, IntrinsicsOutsidePlausibleRangesNameFieldValueAndRange) {
  CameraIntrinsics k;
  EXPECT_TRUE(k.Validate().ok());
  k.fx = 1e12;
  EXPECT_THAT(std::string(k.Validate().message()), HasSubstr("fx=1e+12 px is outside [1, 100000]"));
  k = CameraIntrinsics{};
  k.fy = 0.5;
  EXPECT_THAT(std::string(k.Validate().message()), HasSubstr("fy=0.5 px is outside [1, 100000]"));
  k = CameraIntrinsics{};
  k.cy = -1e9;
  EXPECT_THAT(std::string(k.Validate().message()), HasSubstr("cy=-1e+09 px is outside"));
  k = CameraIntrinsics{};
  k.cx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(k.Validate().code(), absl::StatusCode::kInvalidArgument);
  // A crop may put the principal point outside its own image.
  k = CameraIntrinsics{100, 100, 525.0, 525.0, -180.0, 400.0};
  EXPECT_TRUE(k.Validate().ok()) << k.Validate();
}

TEST(InputBoundsTest, DetectorOptionsNameTheFieldOutOfRange) {
  DetectorOptions options;
  options.box = BoxDims{0.30, 0.20, 0.15};
  EXPECT_TRUE(options.Validate().ok());
  options.max_below_neighbours_m = -0.01;
  EXPECT_THAT(std::string(options.Validate().message()),
              HasSubstr("max_below_neighbours_m=-0.01 is outside [0, 1]"));
  options.max_below_neighbours_m = 0.0;
  EXPECT_TRUE(options.Validate().ok()) << "0 turns the check off";
  options.acceptance.unseen_longer_see_through = 1.5;
  EXPECT_THAT(std::string(options.Validate().message()),
              HasSubstr("acceptance.unseen_longer_see_through must be in [0, 1], got 1.5"));
}

TEST(InputBoundsTest, DetectorRejectsAnAbsurdCameraWithItsField) {
  DetectorOptions options;
  options.box = BoxDims{0.3, 0.2, 0.15};
  options.camera = CameraIntrinsics{};
  options.camera->fx = 1e12;
  PointCloud cloud;
  cloud.xyz = {Eigen::Vector3f(0.0f, 0.0f, 1.0f)};
  cloud.width = 1;
  cloud.height = 1;
  const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
  EXPECT_EQ(det.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(det.status().message()), HasSubstr("fx=1e+12"));
}

// Depths nearer than any camera's become no-return pixels: the frame's boxes
// are found as without them.
TEST(InputBoundsTest, NearZeroDepthsInAFrameAreDroppedAsNoReturn) {
  const absl::StatusOr<BoxDims> dims = BoxModelByName("carton_s");
  ASSERT_TRUE(dims.ok());
  DetectorOptions options;
  options.box = *dims;
  const RenderedScene scene = Render(MakeIsolatedScene(*dims, 3, 1), NoiseOptions{});
  const absl::StatusOr<Detection> clean = DetectBoxes(scene.cloud, options);
  ASSERT_TRUE(clean.ok()) << clean.status();

  PointCloud corrupt = scene.cloud;
  const CameraIntrinsics& k = scene.camera;
  for (int i = 0; i < 40; ++i) {
    const int u = 80 + 12 * i, v = 20 + 10 * i;
    for (float z : {1e-9f, 0.0f, -0.5f}) {
      const int w = u + static_cast<int>(z < 0) + 2 * static_cast<int>(z == 0);
      corrupt.xyz[v * k.width + w] = Eigen::Vector3f(static_cast<float>((w - k.cx) / k.fx) * z,
                                                     static_cast<float>((v - k.cy) / k.fy) * z, z);
    }
  }
  const absl::StatusOr<Detection> det = DetectBoxes(corrupt, options);
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_EQ(det->boxes.size(), clean->boxes.size());

  // The same points in an unorganized cloud (laid onto the camera's grid).
  PointCloud flat = corrupt;
  flat.width = static_cast<int>(flat.xyz.size());
  flat.height = 1;
  options.camera = k;
  const absl::StatusOr<Detection> flat_det = DetectBoxes(flat, options);
  ASSERT_TRUE(flat_det.ok()) << flat_det.status();
  EXPECT_FALSE(flat_det->boxes.empty());
}

// Found by detect_request_fuzzer: a tiny (valid, > 0) edge_lattice_radius_px
// made r_s / it, in pixels, too large for an int, cast before it was clamped
// (undefined behaviour; on x86 the lattice became 1). Now clamped first: the
// same lattice as any radius small enough to reach the cap.
TEST(InputBoundsTest, ATinyLatticeRadiusGivesTheWidestLattice) {
  const absl::StatusOr<BoxDims> dims = BoxModelByName("carton_s");
  ASSERT_TRUE(dims.ok());
  const RenderedScene scene = Render(MakeIsolatedScene(*dims, 3, 1), NoiseOptions{});
  DetectorOptions options;
  options.box = *dims;
  options.edge_lattice_radius_px = 1e-3;  // r_s is ~20 px: 20000, at the cap
  const absl::StatusOr<Detection> capped = DetectBoxes(scene.cloud, options);
  ASSERT_TRUE(capped.ok()) << capped.status();
  options.edge_lattice_radius_px = 1e-35;
  ASSERT_TRUE(options.Validate().ok());
  const absl::StatusOr<Detection> tiny = DetectBoxes(scene.cloud, options);
  ASSERT_TRUE(tiny.ok()) << tiny.status();
  EXPECT_EQ(tiny->edge_points.size(), capped->edge_points.size());
}

// The stall of issue 11: 200 000 identical points sent the detector to the
// k-d tree path, where every radius search returned all 200 000.
TEST(InputBoundsTest, IdenticalPointsCostOneNeighbourEach) {
  constexpr int kPoints = 200000;
  PointCloud cloud;
  cloud.xyz.assign(kPoints, Eigen::Vector3f(0.1f, -0.05f, 1.2f));
  cloud.width = kPoints;
  cloud.height = 1;
  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{});
  ASSERT_TRUE(edges.ok()) << edges.status();
  EXPECT_TRUE(edges->points.empty());
  EXPECT_EQ(edges->kdtree_points, 1u);
  EXPECT_EQ(edges->neighbours_examined, kPoints);

  // Through the detector: too few distinct pixels, so the k-d tree path.
  DetectorOptions options;
  options.box = BoxDims{0.3, 0.2, 0.15};
  const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_TRUE(det->boxes.empty());
}

// A solid block of points 1 mm apart: every ball of r_s = 20 mm held up to
// all 9261 of them. The k-d tree keeps one per 2.5 mm voxel, so a search returns at
// most ~(4/3) pi 8^3 = 2145.
TEST(InputBoundsTest, ADenseBlockCostsABoundedNumberOfNeighboursPerPoint) {
  PointCloud cloud;
  constexpr int kSide = 21;  // 20 mm cube
  for (int i = 0; i < kSide; ++i) {
    for (int j = 0; j < kSide; ++j) {
      for (int l = 0; l < kSide; ++l)
        cloud.xyz.emplace_back(0.001f * i, 0.001f * j, 1.0f + 0.001f * l);
    }
  }
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{});
  ASSERT_TRUE(edges.ok()) << edges.status();
  EXPECT_LE(edges->kdtree_points, 9u * 9u * 9u);
  EXPECT_LE(edges->neighbours_examined, int64_t{2200} * static_cast<int64_t>(cloud.size()));
  EXPECT_GT(edges->neighbours_examined, 0);
}

TEST(InputBoundsTest, KdTreePathRefusesMoreThanItsCap) {
  PointCloud cloud;
  cloud.xyz.assign(kMaxKdTreePoints + 1, Eigen::Vector3f(0.0f, 0.0f, 1.0f));
  cloud.xyz.push_back(Eigen::Vector3f(kNaN, kNaN, kNaN));  // not counted
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  const absl::StatusOr<EdgePoints> edges = DetectEdgePoints(cloud, EdgePointOptions{});
  EXPECT_EQ(edges.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(edges.status().message()),
              HasSubstr("has 1000001 finite points; the k-d tree path scores at most 1000000"));
}

// Found by an adversarial check of the server: 20 000 unorganized points
// sent with a 16384 x 16384 camera were laid onto a grid of 268 M pixels
// (16 s and 4 GB, past any deadline). The grid's size is refused at once,
// naming the intrinsics; a 2048 x 2048 camera is still laid onto.
TEST(InputBoundsTest, AnUnorganizedCloudsCameraGridIsBounded) {
  PointCloud cloud;
  for (int row = 0; row < 100; ++row) {
    for (int col = 0; col < 200; ++col) {
      cloud.xyz.emplace_back(0.001f * col - 0.1f, 0.001f * row - 0.05f, 1.2f);
    }
  }
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  DetectorOptions options;
  options.box = BoxDims{0.30, 0.20, 0.15};
  options.camera = CameraIntrinsics{16384, 16384, 525.0, 525.0, 8192.0, 8192.0};
  const absl::StatusOr<Detection> refused = DetectBoxes(cloud, options);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(refused.status().message()),
              HasSubstr("intrinsics image size 16384 x 16384 is above the 4194304 pixels"));
  options.camera = CameraIntrinsics{2048, 2048, 525.0, 525.0, 1024.0, 1024.0};
  const absl::StatusOr<Detection> laid = DetectBoxes(cloud, options);
  EXPECT_TRUE(laid.ok()) << laid.status();
}

}  // namespace
}  // namespace cornerpose::testing
