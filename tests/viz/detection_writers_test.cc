#include <gtest/gtest.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "common/io/png_io.h"
#include "common/viz/box_wireframe.h"
#include "common/viz/detection_json.h"
#include "common/viz/detection_ply.h"
#include "common/viz/detection_png.h"

namespace cornerpose {
namespace {

namespace fs = std::filesystem;

// A small scene: a 64 x 48 camera looking at a floor 1 m away with one box
// of 0.3 x 0.2 x 0.1 m lying on it, seen from above.
class DetectionWritersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("detection_writers_test_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));  // concurrent runs from other build dirs
    fs::remove_all(dir_);
    fs::create_directories(dir_);

    camera_ = CameraIntrinsics{64, 48, 50.0, 50.0, 31.5, 23.5};
    dims_ = BoxDims{0.3, 0.2, 0.1};
    cloud_.width = camera_.width;
    cloud_.height = camera_.height;
    for (int v = 0; v < camera_.height; ++v) {
      for (int u = 0; u < camera_.width; ++u) {
        const double x = (u - camera_.cx) / camera_.fx, y = (v - camera_.cy) / camera_.fy;
        // Box top at z = 0.9 over |x z| < 0.15, |y z| < 0.1; floor at 1.0.
        double z = 1.0;
        if (std::abs(x * 0.9) < 0.15 && std::abs(y * 0.9) < 0.1) z = 0.9;
        cloud_.xyz.emplace_back(x * z, y * z, z);
      }
    }
    cloud_.xyz[0] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());

    DetectedBox box;
    box.camera_T_box.translation() = Eigen::Vector3d(0.0, 0.0, 0.95);
    box.camera_T_box.linear() =
        Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).matrix();
    box.score = 0.875;
    box.grasp_face = BoxFace::kPlusZ;
    box.grasp_centre_camera = Eigen::Vector3d(0.0, 0.0, 0.9);
    box.grasp_normal_camera = Eigen::Vector3d(0.0, 0.0, -1.0);
    box.segments = {0};
    box.num_corners = 1;
    detection_.boxes.push_back(box);

    EdgeSegment segment;
    segment.end1 = Eigen::Vector3f(-0.15f, -0.1f, 0.9f);
    segment.end2 = Eigen::Vector3f(0.15f, -0.1f, 0.9f);
    segment.point = segment.end1;
    segment.direction = Eigen::Vector3f::UnitX();
    segment.num_points = 12;
    detection_.segments.push_back(segment);

    Corner corner;
    corner.position = Eigen::Vector3f(-0.15f, -0.1f, 0.9f);
    corner.segment_a = 0;
    corner.segment_b = 0;
    detection_.corners.push_back(corner);

    detection_.edge_points = {{-0.1f, -0.1f, 0.9f}, {0.0f, -0.1f, 0.9f}, {0.1f, -0.1f, 0.9f}};
    detection_.timings = StageTimings{1.0, 2.0, 3.0, 4.0, 5.0, 15.5};
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
  CameraIntrinsics camera_;
  BoxDims dims_;
  PointCloud cloud_;
  Detection detection_;
};

TEST_F(DetectionWritersTest, JsonHoldsPoseRowMajorAndScorerDetections) {
  ASSERT_TRUE(WriteDetectionJson(Path("d.json"), detection_, dims_).ok());
  std::ifstream in(Path("d.json"));
  const nlohmann::json j = nlohmann::json::parse(in);

  EXPECT_EQ(j["box_dims"], nlohmann::json({0.3, 0.2, 0.1}));
  ASSERT_EQ(j["boxes"].size(), 1u);
  const nlohmann::json& pose = j["boxes"][0]["camera_T_box"];
  ASSERT_EQ(pose.size(), 4u);
  const Eigen::Matrix4d m = detection_.boxes[0].camera_T_box.matrix();
  for (int r = 0; r < 4; ++r) {
    ASSERT_EQ(pose[r].size(), 4u);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(pose[r][c].get<double>(), m(r, c), 1e-12);
  }
  EXPECT_DOUBLE_EQ(pose[2][3].get<double>(), 0.95);  // translation in the last column
  EXPECT_EQ(j["boxes"][0]["grasp_face"], "+z");
  EXPECT_EQ(j["boxes"][0]["grasp_centre"], nlohmann::json({0.0, 0.0, 0.9}));
  EXPECT_EQ(j["boxes"][0]["num_corners"], 1);
  EXPECT_EQ(j["boxes"][0]["proposed_by"], "corner");
  EXPECT_DOUBLE_EQ(j["boxes"][0]["score"].get<double>(), 0.875);

  ASSERT_EQ(j["edges"].size(), 1u);
  EXPECT_EQ(j["edges"][0]["num_points"], 12);
  EXPECT_NEAR(j["edges"][0]["length"].get<double>(), 0.3, 1e-6);
  EXPECT_EQ(j["edges"][0]["end2"].size(), 3u);
  ASSERT_EQ(j["corners"].size(), 1u);
  EXPECT_EQ(j["corners"][0]["segments"], nlohmann::json({0, 0}));
  EXPECT_EQ(j["num_edge_points"], 3);
  EXPECT_DOUBLE_EQ(j["timings_ms"]["clubbing"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(j["timings_ms"]["total"].get<double>(), 15.5);

  // The scorer's per-scene format.
  ASSERT_EQ(j["detections"].size(), 1u);
  EXPECT_EQ(j["detections"][0]["pose"], pose);
  EXPECT_DOUBLE_EQ(j["detections"][0]["score"].get<double>(), 0.875);
  EXPECT_DOUBLE_EQ(j["time_s"].get<double>(), 0.0155);
}

// What proposed each box: a planar patch, a corner, two parallel edges (a
// segment pair and no corner), or a box found beside it (neither).
TEST_F(DetectionWritersTest, JsonSaysWhatProposedEachBox) {
  Detection d = detection_;
  d.boxes.resize(4, detection_.boxes[0]);
  d.boxes[0].from_face = true;
  d.boxes[2].num_corners = 0;
  d.boxes[2].segments = {0, 1};
  d.boxes[3].num_corners = 0;
  d.boxes[3].segments.clear();
  ASSERT_TRUE(WriteDetectionJson(Path("p.json"), d, dims_).ok());
  std::ifstream in(Path("p.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["boxes"].size(), 4u);
  EXPECT_EQ(j["boxes"][0]["proposed_by"], "face");
  EXPECT_EQ(j["boxes"][1]["proposed_by"], "corner");
  EXPECT_EQ(j["boxes"][2]["proposed_by"], "edges");
  EXPECT_EQ(j["boxes"][3]["proposed_by"], "neighbour");
}

TEST_F(DetectionWritersTest, JsonOfAnEmptyDetectionHasEmptyLists) {
  const nlohmann::json j = DetectionToJson(Detection{}, dims_);
  EXPECT_TRUE(j["boxes"].is_array() && j["boxes"].empty());
  EXPECT_TRUE(j["detections"].is_array() && j["detections"].empty());
  EXPECT_TRUE(j["edges"].is_array() && j["corners"].is_array());
  EXPECT_EQ(j["num_edge_points"], 0);
}

bool Near(const pcl::PointXYZRGB& p, const Eigen::Vector3d& q, double tol) {
  return (Eigen::Vector3d(p.x, p.y, p.z) - q).norm() < tol;
}

TEST_F(DetectionWritersTest, PlyReadsBackWithColouredParts) {
  ASSERT_TRUE(WriteDetectionPly(Path("d.ply"), cloud_, detection_, dims_).ok());
  pcl::PointCloud<pcl::PointXYZRGB> ply;
  pcl::PLYReader reader;
  ASSERT_EQ(reader.read(Path("d.ply"), ply), 0);

  size_t grey = 0, red = 0, green = 0, yellow = 0, blue = 0;
  bool green_at_corner = false, yellow_at_corner = false, blue_on_segment = false;
  bool red_at_edge_point = false;
  const std::array<Eigen::Vector3d, 8> corners =
      BoxCornersCamera(detection_.boxes[0].camera_T_box, dims_);
  for (const pcl::PointXYZRGB& p : ply) {
    if (p.r == 128 && p.g == 128 && p.b == 128) {
      ++grey;
    } else if (p.r == 255 && p.g == 0 && p.b == 0) {
      ++red;
      red_at_edge_point |= Near(p, Eigen::Vector3d(0.0, -0.1, 0.9), 1e-6);
    } else if (p.r == 0 && p.g == 255 && p.b == 0) {
      ++green;
      green_at_corner |= Near(p, corners[7], 1e-4);
    } else if (p.r == 255 && p.g == 255 && p.b == 0) {
      ++yellow;
      yellow_at_corner |= Near(p, Eigen::Vector3d(-0.15, -0.1, 0.9), 0.006);
    } else if (p.r == 0 && p.b == 255) {
      ++blue;
      blue_on_segment |= Near(p, Eigen::Vector3d(0.0, -0.1, 0.9), 0.001);
    }
  }
  EXPECT_EQ(grey, cloud_.size() - 1);  // all but the NaN pixel
  EXPECT_EQ(red, detection_.edge_points.size());
  // 4 edges of 0.3 m, 4 of 0.2 m, 4 of 0.1 m at 1 mm: about 2400 points.
  EXPECT_NEAR(static_cast<double>(green), 2412.0, 30.0);
  EXPECT_GE(blue, 300u);
  EXPECT_GE(yellow, 30u);
  EXPECT_TRUE(green_at_corner);
  EXPECT_TRUE(yellow_at_corner);
  EXPECT_TRUE(blue_on_segment);
  EXPECT_TRUE(red_at_edge_point);
}

TEST_F(DetectionWritersTest, PngHasTheImageSizeAndGreenWhereTheBoxProjects) {
  ASSERT_TRUE(WriteDetectionPng(Path("d.png"), cloud_, camera_, detection_, dims_).ok());
  int w = 0, h = 0;
  absl::StatusOr<std::vector<uint8_t>> rgb = ReadRgbPng(Path("d.png"), &w, &h);
  ASSERT_TRUE(rgb.ok()) << rgb.status();
  ASSERT_EQ(w, camera_.width);
  ASSERT_EQ(h, camera_.height);
  auto pixel = [&](int u, int v) {
    const size_t i = (static_cast<size_t>(v) * w + u) * 3;
    return std::array<uint8_t, 3>{(*rgb)[i], (*rgb)[i + 1], (*rgb)[i + 2]};
  };
  auto is_green = [](const std::array<uint8_t, 3>& c) {
    return c[0] == 0 && c[1] == 255 && c[2] == 0;
  };
  // A bottom corner (z = 1.0 m) of the box: (0.15, 0.1, 1.0) projects to
  // (31.5 + 7.5, 23.5 + 5) = (39, 28.5); some pixel around it is green.
  bool green_near_corner = false;
  for (int dv = -1; dv <= 1; ++dv) {
    for (int du = -1; du <= 1; ++du) green_near_corner |= is_green(pixel(39 + du, 28 + dv));
  }
  EXPECT_TRUE(green_near_corner);
  // The middle of the long top edge at y = -0.1, z = 0.9 projects near
  // v = 23.5 - 5.6 = 17.9; it is covered by the blue segment or green box.
  const std::array<uint8_t, 3> mid = pixel(31, 18);
  EXPECT_TRUE(is_green(mid) || (mid[0] == 0 && mid[2] == 255))
      << int(mid[0]) << "," << int(mid[1]) << "," << int(mid[2]);
  // The NaN pixel in the corner is black; floor pixels are grey.
  EXPECT_EQ(pixel(0, 0), (std::array<uint8_t, 3>{0, 0, 0}));
  const std::array<uint8_t, 3> floor = pixel(2, 45);
  EXPECT_EQ(floor[0], floor[1]);
  EXPECT_EQ(floor[1], floor[2]);
  EXPECT_GT(floor[0], 0);
  // The box top (nearer) is brighter than the floor.
  EXPECT_GT(pixel(31, 23)[0], floor[0]);
  // The corner cross is yellow.
  bool yellow = false;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const auto c = pixel(u, v);
      yellow |= c[0] == 255 && c[1] == 255 && c[2] == 0;
    }
  }
  EXPECT_TRUE(yellow);
}

TEST_F(DetectionWritersTest, PngFromUnorganizedCloudProjectsPoints) {
  PointCloud flat;
  for (const Eigen::Vector3f& p : cloud_.xyz) {
    if (PointCloud::IsValid(p)) flat.xyz.push_back(p);
  }
  flat.width = static_cast<int>(flat.xyz.size());
  flat.height = 1;
  ASSERT_TRUE(WriteDetectionPng(Path("flat.png"), flat, camera_, detection_, dims_).ok());
  int w = 0, h = 0;
  absl::StatusOr<std::vector<uint8_t>> rgb = ReadRgbPng(Path("flat.png"), &w, &h);
  ASSERT_TRUE(rgb.ok()) << rgb.status();
  ASSERT_EQ(w, 64);
  ASSERT_EQ(h, 48);
  const size_t floor = (static_cast<size_t>(45) * w + 2) * 3;
  EXPECT_GT((*rgb)[floor], 0);
}

TEST_F(DetectionWritersTest, BoxBehindTheCameraDoesNotBreakThePng) {
  Detection odd = detection_;
  odd.boxes[0].camera_T_box.translation() = Eigen::Vector3d(0.0, 0.0, 0.02);
  odd.boxes.push_back(detection_.boxes[0]);
  odd.boxes.back().camera_T_box.translation() = Eigen::Vector3d(1e6, -1e6, -5.0);
  odd.segments[0].end2 = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  EXPECT_TRUE(WriteDetectionPng(Path("odd.png"), cloud_, camera_, odd, dims_).ok());
  EXPECT_TRUE(WriteDetectionPly(Path("odd.ply"), cloud_, odd, dims_).ok());
}

TEST_F(DetectionWritersTest, UnwritablePathsReturnErrors) {
  const std::string bad = Path("no_such_dir/out");
  EXPECT_FALSE(WriteDetectionJson(bad + ".json", detection_, dims_).ok());
  EXPECT_FALSE(WriteDetectionPly(bad + ".ply", cloud_, detection_, dims_).ok());
  EXPECT_FALSE(WriteDetectionPng(bad + ".png", cloud_, camera_, detection_, dims_).ok());
  CameraIntrinsics broken = camera_;
  broken.fx = 0;
  EXPECT_EQ(WriteDetectionPng(Path("x.png"), cloud_, broken, detection_, dims_).code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cornerpose
