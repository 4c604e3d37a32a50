#include "server/service/detect_request.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "common/perception/detector.h"

namespace cornerpose::server {
namespace {

using ::testing::HasSubstr;

v1::DetectRequest WithBox(double l, double b, double h) {
  v1::DetectRequest request;
  request.mutable_box()->set_l(l);
  request.mutable_box()->set_b(b);
  request.mutable_box()->set_h(h);
  return request;
}

TEST(DetectorOptionsFromRequestTest, ExplicitBoxAndOverrides) {
  v1::DetectRequest request = WithBox(0.3, 0.2, 0.15);
  request.mutable_overrides()->set_edge_radius_m(0.03);
  request.mutable_overrides()->set_edge_threshold(0.4);
  request.mutable_overrides()->set_ransac_threshold_m(0.005);
  absl::StatusOr<DetectorOptions> options = DetectorOptionsFromRequest(request, {});
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->box.l, 0.3);
  EXPECT_EQ(options->box.h, 0.15);
  EXPECT_EQ(options->edge_points.radius_m, 0.03);
  EXPECT_EQ(options->segments.gap_m, 0.03);
  EXPECT_EQ(options->edge_points.threshold, 0.4);
  EXPECT_EQ(options->segments.ransac_threshold_m, 0.005);
}

TEST(DetectorOptionsFromRequestTest, UnsetOverridesKeepDefaults) {
  DetectorOptions defaults;
  defaults.edge_points.threshold = 0.31;
  absl::StatusOr<DetectorOptions> options =
      DetectorOptionsFromRequest(WithBox(0.3, 0.2, 0.15), defaults);
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->edge_points.threshold, 0.31);
}

TEST(DetectorOptionsFromRequestTest, ModelName) {
  v1::DetectRequest request;
  request.set_box_model("carton_l");
  absl::StatusOr<DetectorOptions> options = DetectorOptionsFromRequest(request, {});
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->box.l, 0.40);
  EXPECT_EQ(options->box.b, 0.30);
  EXPECT_EQ(options->box.h, 0.25);
}

TEST(DetectorOptionsFromRequestTest, ServerModelsComeBeforeBuiltInOnes) {
  const BoxModels models = {{"crate", {0.5, 0.4, 0.3}}, {"carton_l", {0.41, 0.31, 0.26}}};
  v1::DetectRequest request;
  request.set_box_model("crate");
  absl::StatusOr<DetectorOptions> crate = DetectorOptionsFromRequest(request, {}, models);
  ASSERT_TRUE(crate.ok()) << crate.status();
  EXPECT_EQ(crate->box.l, 0.5);
  request.set_box_model("carton_l");
  absl::StatusOr<DetectorOptions> carton = DetectorOptionsFromRequest(request, {}, models);
  ASSERT_TRUE(carton.ok()) << carton.status();
  EXPECT_EQ(carton->box.l, 0.41);
  // Without the server's models the built-in size applies.
  EXPECT_EQ(DetectorOptionsFromRequest(request, {})->box.l, 0.40);
}

TEST(DetectorOptionsFromRequestTest, RefusedBoxes) {
  struct Case {
    v1::DetectRequest request;
    std::string message;
  };
  v1::DetectRequest unknown;
  unknown.set_box_model("crate");
  const Case cases[] = {
      {WithBox(0.3, 0.0, 0.15), "box size b=0 m must be positive"},
      {WithBox(-0.3, 0.2, 0.15), "box size l=-0.3 m must be positive"},
      {WithBox(0.3, 0.2, 11), "above the 10 m limit"},
      // A tiny box named the edge radius derived from it (rounded to 0).
      {WithBox(0.3, 1e-9, 0.15), "box size b=1e-09 m is below the 5 mm limit"},
      {unknown, "unknown box model 'crate'"},
      {v1::DetectRequest(), "request has no box size"},
  };
  for (const Case& c : cases) {
    absl::Status s = DetectorOptionsFromRequest(c.request, {}).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(s.message(), HasSubstr(c.message));
  }
}

TEST(DetectorOptionsFromRequestTest, OutOfRangeOverrideIsInvalid) {
  v1::DetectRequest request = WithBox(0.3, 0.2, 0.15);
  request.mutable_overrides()->set_edge_radius_m(-1.0);
  EXPECT_EQ(DetectorOptionsFromRequest(request, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(CloudFromRequestTest, SourceIsNotFoundAndNoInputIsInvalid) {
  v1::DetectRequest request;
  request.set_source("cell_1");
  absl::Status s = CloudFromRequest(request).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(s.message(), "unknown source 'cell_1'");

  s = CloudFromRequest(v1::DetectRequest()).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("request has no input"));
}

TEST(CloudFromRequestTest, DepthImageUsesRequestIntrinsics) {
  v1::DetectRequest request;
  v1::DepthImage* image = request.mutable_depth_image();
  image->set_width(1);
  image->set_height(1);
  image->set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  image->set_data(std::string("\xe8\x03", 2));  // 1000 mm
  EXPECT_EQ(CloudFromRequest(request).status().code(), absl::StatusCode::kInvalidArgument);

  request.mutable_intrinsics()->set_width(1);
  request.mutable_intrinsics()->set_height(1);
  request.mutable_intrinsics()->set_fx(500);
  request.mutable_intrinsics()->set_fy(500);
  absl::StatusOr<PointCloud> cloud = CloudFromRequest(request);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), 1u);
  EXPECT_FLOAT_EQ(cloud->xyz[0].z(), 1.0f);
}

TEST(DetectorOptionsFromRequestTest, StreamRequestsResolveTheSameWay) {
  const BoxModels models = {{"crate", {0.5, 0.4, 0.3}}};
  v1::StreamDetectionsRequest request;
  request.set_source("cell");
  request.set_box_model("crate");
  request.mutable_overrides()->set_edge_radius_m(0.025);
  absl::StatusOr<DetectorOptions> options = DetectorOptionsFromRequest(request, {}, models);
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->box.l, 0.5);
  // r_s and the segment gap stay tied.
  EXPECT_EQ(options->edge_points.radius_m, 0.025);
  EXPECT_EQ(options->segments.gap_m, 0.025);

  request.clear_box_model();
  absl::Status s = DetectorOptionsFromRequest(request, {}).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("request has no box size"));
}

// An organized cloud is its camera's grid: intrinsics of another size were
// ignored without a word; of its own size (or none) they are fine.
TEST(CloudFromRequestTest, IntrinsicsOfAnotherSizeThanAnOrganizedCloudAreRefused) {
  v1::DetectRequest request;
  v1::PointCloud* cloud = request.mutable_cloud();
  const float xyz[12] = {0, 0, 1, 0.1f, 0, 1, 0, 0.1f, 1, 0.1f, 0.1f, 1};
  cloud->set_xyz(std::string(reinterpret_cast<const char*>(xyz), sizeof(xyz)));
  cloud->set_width(2);
  cloud->set_height(2);
  EXPECT_TRUE(CloudFromRequest(request).ok());
  v1::CameraIntrinsics* k = request.mutable_intrinsics();
  k->set_width(2);
  k->set_height(2);
  k->set_fx(500);
  k->set_fy(500);
  EXPECT_TRUE(CloudFromRequest(request).ok());
  k->set_width(4);
  const absl::Status s = CloudFromRequest(request).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(),
              HasSubstr("intrinsics image size 4 x 2 differs from the organized cloud's 2 x 2"));
}

TEST(CloudFromRequestTest, ColourImageBecomesTheCloudsColour) {
  v1::DetectRequest request;
  v1::PointCloud* cloud = request.mutable_cloud();
  const float xyz[6] = {0, 0, 1, 0.1f, 0, 1};
  cloud->set_xyz(std::string(reinterpret_cast<const char*>(xyz), sizeof(xyz)));
  cloud->set_width(2);
  cloud->set_height(1);
  v1::ColorImage* color = request.mutable_color();
  color->set_width(2);
  color->set_height(1);
  color->set_encoding(v1::COLOR_ENCODING_RGB8);
  color->set_data(std::string("\xff\x00\x00\x00\x00\xff", 6));
  absl::StatusOr<PointCloud> with_color = CloudFromRequest(request);
  ASSERT_TRUE(with_color.ok()) << with_color.status();
  EXPECT_EQ(with_color->rgb, (std::vector<uint32_t>{0x00ff0000u, 0x000000ffu}));

  // Colour twice (cloud.rgb and color) is refused.
  cloud->set_rgb(std::string(6, '\0'));
  absl::Status s = CloudFromRequest(request).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("cloud.rgb or color, not both"));
}

// A serialized DetectRequest from a file (a fuzzer's seed or finding);
// false when the file is missing or does not parse.
bool ReadRequest(const std::string& path, v1::DetectRequest* request) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::stringstream bytes;
  bytes << in.rdbuf();
  return request->ParseFromString(bytes.str());
}

// The DetectRequest fuzzer's seeds (fuzz/corpus/detect_request_fuzzer,
// written by fuzz/make_seeds.py) are requests the service serves: each one
// parses, converts and, but for the unknown source, is detected. A seed
// that no longer reaches the detector would leave the fuzzer at the door.
TEST(DetectRequestFuzzSeedsTest, EverySeedReachesTheDetector) {
  const std::string dir =
      std::string(CORNERPOSE_SOURCE_DIR) + "/fuzz/corpus/detect_request_fuzzer/";
  for (const char* name :
       {"depth_mm_carton.bin", "depth_m_grey_overrides.bin", "organized_cloud_rgb.bin",
        "unorganized_cloud_camera.bin", "source.bin"}) {
    SCOPED_TRACE(name);
    v1::DetectRequest request;
    ASSERT_TRUE(ReadRequest(dir + name, &request)) << "missing or unreadable " << dir << name;
    absl::StatusOr<DetectorOptions> options = DetectorOptionsFromRequest(request, {});
    ASSERT_TRUE(options.ok()) << options.status();
    absl::StatusOr<PointCloud> cloud = CloudFromRequest(request);
    if (request.input_case() == v1::DetectRequest::kSource) {
      EXPECT_EQ(cloud.status().code(), absl::StatusCode::kNotFound);
      continue;
    }
    ASSERT_TRUE(cloud.ok()) << cloud.status();
    EXPECT_GE(cloud->size(), 200u);
    EXPECT_EQ(cloud->has_color(), request.has_color() || !request.cloud().rgb().empty());
    absl::StatusOr<Detection> detection = DetectBoxes(*cloud, *options);
    ASSERT_TRUE(detection.ok()) << detection.status();
    // The depth seeds show the carton whole: the fuzzer starts inside the
    // judge, not only in the edge stage.
    if (request.input_case() == v1::DetectRequest::kDepthImage) {
      EXPECT_EQ(detection->boxes.size(), 1u);
    }
  }
}

// Findings of detect_request_fuzzer (tests/data/fuzz/), served again: an
// unorganized cloud of 200 points, most at depths near 1e-38 m, too few in
// the camera's range to project, so its own depths set the frame's median:
// r_s in pixels, f r_s / median, was too large for an int when cast before
// it was clamped (undefined behaviour in the edge lattice's step).
TEST(DetectRequestFuzzSeedsTest, FindingsAreServedWithAStatus) {
  const std::string path =
      std::string(CORNERPOSE_SOURCE_DIR) + "/tests/data/fuzz/detect_request_tiny_lattice.bin";
  v1::DetectRequest request;
  ASSERT_TRUE(ReadRequest(path, &request)) << "missing or unreadable " << path;
  absl::StatusOr<DetectorOptions> options = DetectorOptionsFromRequest(request, {});
  ASSERT_TRUE(options.ok()) << options.status();
  absl::StatusOr<PointCloud> cloud = CloudFromRequest(request);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  float z_min = std::numeric_limits<float>::max();
  for (const Eigen::Vector3f& p : cloud->xyz) {
    if (std::isfinite(p.z()) && p.z() > 0.0f) z_min = std::min(z_min, p.z());
  }
  EXPECT_LT(z_min, 1e-30f) << "the input no longer reaches the case";
  EXPECT_TRUE(DetectBoxes(*cloud, *options).ok());
}

}  // namespace
}  // namespace cornerpose::server
