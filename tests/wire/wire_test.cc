#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "common/perception/detector.h"
#include "common/wire/box_wire.h"
#include "common/wire/cloud_wire.h"
#include "common/wire/detection_wire.h"
#include "common/wire/geometry_wire.h"

namespace cornerpose::wire {
namespace {

using ::testing::HasSubstr;

std::string Pack(const std::vector<Eigen::Vector3f>& points) {
  std::string bytes(points.size() * 12, '\0');
  for (size_t i = 0; i < points.size(); ++i) {
    const float p[3] = {points[i].x(), points[i].y(), points[i].z()};
    std::memcpy(bytes.data() + i * 12, p, 12);
  }
  return bytes;
}

v1::CameraIntrinsics Intrinsics(uint32_t width, uint32_t height) {
  v1::CameraIntrinsics k;
  k.set_width(width);
  k.set_height(height);
  k.set_fx(500.0);
  k.set_fy(400.0);
  k.set_cx(1.0);
  k.set_cy(0.5);
  return k;
}

TEST(QuaternionTest, NinetyDegreesAboutZ) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  const v1::Quaternion p = ToProto(q);
  EXPECT_NEAR(p.w(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 0.0, 1e-12);
  EXPECT_NEAR(p.z(), std::sqrt(0.5), 1e-12);
}

TEST(QuaternionTest, SignIsChosenWithNonNegativeW) {
  // -q is the same rotation; the message always carries w >= 0.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(3.0, Eigen::Vector3d(1, 2, 3).normalized()));
  const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  const v1::Quaternion p = ToProto(minus_q);
  EXPECT_GE(p.w(), 0.0);
  EXPECT_NEAR(p.w(), q.w(), 1e-12);
  EXPECT_NEAR(p.z(), q.z(), 1e-12);
}

TEST(PoseTest, RotationMatrixBecomesUnitQuaternionThatRotatesTheSame) {
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  camera_T_box.linear() = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) *
                           Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()))
                              .toRotationMatrix();
  camera_T_box.translation() = Eigen::Vector3d(0.1, -0.2, 1.3);
  const v1::Pose pose = ToProto(camera_T_box);
  EXPECT_DOUBLE_EQ(pose.position().x(), 0.1);
  EXPECT_DOUBLE_EQ(pose.position().y(), -0.2);
  EXPECT_DOUBLE_EQ(pose.position().z(), 1.3);
  const v1::Quaternion& o = pose.orientation();
  const Eigen::Quaterniond q(o.w(), o.x(), o.y(), o.z());
  EXPECT_NEAR(q.norm(), 1.0, 1e-12);
  EXPECT_TRUE(q.toRotationMatrix().isApprox(camera_T_box.rotation(), 1e-12));
}

TEST(BoxFaceTest, EveryFaceHasItsOwnValue) {
  EXPECT_EQ(ToProto(BoxFace::kPlusX), v1::BOX_FACE_PLUS_X);
  EXPECT_EQ(ToProto(BoxFace::kMinusX), v1::BOX_FACE_MINUS_X);
  EXPECT_EQ(ToProto(BoxFace::kPlusY), v1::BOX_FACE_PLUS_Y);
  EXPECT_EQ(ToProto(BoxFace::kMinusY), v1::BOX_FACE_MINUS_Y);
  EXPECT_EQ(ToProto(BoxFace::kPlusZ), v1::BOX_FACE_PLUS_Z);
  EXPECT_EQ(ToProto(BoxFace::kMinusZ), v1::BOX_FACE_MINUS_Z);
}

TEST(CloudFromProtoTest, UnpacksOrganizedCloudWithNaN) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  v1::PointCloud msg;
  msg.set_xyz(Pack({{1, 2, 3}, {nan, nan, nan}, {-1, 0.5f, 2}, {0, 0, 1}}));
  msg.set_width(2);
  msg.set_height(2);
  absl::StatusOr<PointCloud> cloud = CloudFromProto(msg);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_EQ(cloud->width, 2);
  EXPECT_EQ(cloud->height, 2);
  ASSERT_EQ(cloud->size(), 4u);
  EXPECT_EQ(cloud->xyz[2], Eigen::Vector3f(-1, 0.5f, 2));
  EXPECT_TRUE(std::isnan(cloud->xyz[1].z()));
}

TEST(CloudFromProtoTest, EmptyMessageIsEmptyCloud) {
  absl::StatusOr<PointCloud> cloud = CloudFromProto(v1::PointCloud());
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_TRUE(cloud->empty());
}

TEST(CloudFromProtoTest, ByteLengthNotMultipleOf12) {
  v1::PointCloud msg;
  msg.set_xyz(std::string(25, '\0'));
  msg.set_width(2);
  msg.set_height(1);
  absl::Status s = CloudFromProto(msg).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("25 bytes, not a multiple of 12"));
}

TEST(CloudFromProtoTest, WidthTimesHeightMismatch) {
  v1::PointCloud msg;
  msg.set_xyz(Pack({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}}));
  msg.set_width(2);
  msg.set_height(2);
  absl::Status s = CloudFromProto(msg).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("width * height (2 * 2 = 4) does not match its 3 points"));
}

TEST(CloudFromProtoTest, ZeroWidthWithPointsIsMismatch) {
  v1::PointCloud msg;
  msg.set_xyz(Pack({{0, 0, 1}}));
  EXPECT_EQ(CloudFromProto(msg).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(CloudFromProtoTest, AbsurdSizeIsRefused) {
  v1::PointCloud msg;
  msg.set_xyz(std::string((kMaxPoints + 1) * 12, '\0'));
  msg.set_width(static_cast<uint32_t>(kMaxPoints + 1));
  msg.set_height(1);
  absl::Status s = CloudFromProto(msg).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("20000001 points, above the limit of 20000000"));
}

TEST(DepthImageTest, WithoutIntrinsicsIsInvalid) {
  v1::DepthImage image;
  image.set_width(2);
  image.set_height(2);
  image.set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  image.set_data(std::string(8, '\0'));
  absl::Status s = CloudFromDepthImage(image, nullptr).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("depth_image needs intrinsics"));
}

TEST(DepthImageTest, SizeMustMatchIntrinsics) {
  v1::DepthImage image;
  image.set_width(3);
  image.set_height(2);
  image.set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  image.set_data(std::string(12, '\0'));
  const v1::CameraIntrinsics k = Intrinsics(2, 2);
  absl::Status s = CloudFromDepthImage(image, &k).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("depth_image is 3 x 2 but the intrinsics are for 2 x 2"));
}

TEST(DepthImageTest, UnspecifiedEncodingAndShortDataAreInvalid) {
  v1::DepthImage image;
  image.set_width(2);
  image.set_height(2);
  image.set_data(std::string(8, '\0'));
  const v1::CameraIntrinsics k = Intrinsics(2, 2);
  absl::Status s = CloudFromDepthImage(image, &k).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("encoding 0 is not"));

  image.set_encoding(v1::DEPTH_ENCODING_FLOAT32_M);
  s = CloudFromDepthImage(image, &k).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("data has 8 bytes; 2 x 2 samples of 4 bytes need 16"));
}

TEST(DepthImageTest, Uint16MillimetresBackProject) {
  const uint16_t depth[4] = {1000, 0, 2000, 1500};
  v1::DepthImage image;
  image.set_width(2);
  image.set_height(2);
  image.set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  image.set_data(std::string(reinterpret_cast<const char*>(depth), sizeof(depth)));
  const v1::CameraIntrinsics k = Intrinsics(2, 2);
  absl::StatusOr<PointCloud> cloud = CloudFromDepthImage(image, &k);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), 4u);
  EXPECT_EQ(cloud->width, 2);
  EXPECT_EQ(cloud->height, 2);
  EXPECT_TRUE(std::isnan(cloud->xyz[1].z()));
  // Pixel (u=0, v=1) at 2 m: x = (0 - 1) * 2 / 500, y = (1 - 0.5) * 2 / 400.
  EXPECT_NEAR(cloud->xyz[2].x(), -0.004f, 1e-6f);
  EXPECT_NEAR(cloud->xyz[2].y(), 0.0025f, 1e-6f);
  EXPECT_NEAR(cloud->xyz[2].z(), 2.0f, 1e-6f);
}

TEST(DepthImageTest, Float32MetresBackProject) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float depth[4] = {1.25f, nan, 0.0f, 2.5f};
  v1::DepthImage image;
  image.set_width(2);
  image.set_height(2);
  image.set_encoding(v1::DEPTH_ENCODING_FLOAT32_M);
  image.set_data(std::string(reinterpret_cast<const char*>(depth), sizeof(depth)));
  const v1::CameraIntrinsics k = Intrinsics(2, 2);
  absl::StatusOr<PointCloud> cloud = CloudFromDepthImage(image, &k);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_TRUE(std::isnan(cloud->xyz[1].z()));
  EXPECT_TRUE(std::isnan(cloud->xyz[2].z()));
  // Pixel (u=1, v=1) at 2.5 m: x = 0, y = 0.5 * 2.5 / 400.
  EXPECT_NEAR(cloud->xyz[3].x(), 0.0f, 1e-7f);
  EXPECT_NEAR(cloud->xyz[3].y(), 0.003125f, 1e-7f);
  EXPECT_FLOAT_EQ(cloud->xyz[3].z(), 2.5f);
  EXPECT_NEAR(cloud->xyz[0].x(), -0.0025f, 1e-7f);
}

TEST(DetectionToProtoTest, EdgePointsOnlyWhenAsked) {
  Detection detection;
  detection.edge_points = {{1, 2, 3}};
  DetectedBox box;
  box.score = 0.75;
  box.grasp_face = BoxFace::kMinusY;
  box.grasp_normal_camera = Eigen::Vector3d(0, 0, -1);
  detection.boxes.push_back(box);
  EdgeSegment segment;
  segment.end2 = Eigen::Vector3f(0.3f, 0, 1);
  segment.num_points = 40;
  detection.segments.push_back(segment);
  detection.timings.total_ms = 12.5;

  v1::DetectResponse without = DetectionToProto(detection, false);
  EXPECT_EQ(without.edge_points_size(), 0);
  ASSERT_EQ(without.boxes_size(), 1);
  EXPECT_EQ(without.boxes(0).score(), 0.75);
  EXPECT_EQ(without.boxes(0).grasp_face(), v1::BOX_FACE_MINUS_Y);
  EXPECT_EQ(without.boxes(0).grasp_normal().z(), -1.0);
  EXPECT_EQ(without.boxes(0).camera_pose_box().orientation().w(), 1.0);
  ASSERT_EQ(without.segments_size(), 1);
  EXPECT_EQ(without.segments(0).num_points(), 40u);
  EXPECT_FLOAT_EQ(static_cast<float>(without.segments(0).end2().x()), 0.3f);
  EXPECT_EQ(without.timings().total_ms(), 12.5);

  v1::DetectResponse with = DetectionToProto(detection, true);
  ASSERT_EQ(with.edge_points_size(), 1);
  EXPECT_EQ(with.edge_points(0).z(), 3.0);
}

TEST(DetectionFromProtoTest, RoundTripKeepsBoxesSegmentsAndTimings) {
  Detection detection;
  DetectedBox box;
  box.camera_T_box.linear() =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  box.camera_T_box.translation() = Eigen::Vector3d(0.1, 0.2, 1.1);
  box.score = 0.9;
  box.grasp_face = BoxFace::kPlusY;
  box.grasp_centre_camera = Eigen::Vector3d(0.1, 0.1, 1.0);
  detection.boxes.push_back(box);
  EdgeSegment segment;
  segment.end1 = Eigen::Vector3f(0, 0, 1);
  segment.end2 = Eigen::Vector3f(0.2f, 0, 1);
  segment.num_points = 12;
  detection.segments.push_back(segment);
  detection.timings.poses_ms = 3.5;

  absl::StatusOr<Detection> back = DetectionFromProto(DetectionToProto(detection, false));
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->boxes.size(), 1u);
  EXPECT_TRUE(back->boxes[0].camera_T_box.isApprox(box.camera_T_box, 1e-12));
  EXPECT_EQ(back->boxes[0].grasp_face, BoxFace::kPlusY);
  EXPECT_EQ(back->boxes[0].score, 0.9);
  ASSERT_EQ(back->segments.size(), 1u);
  EXPECT_TRUE(back->segments[0].direction.isApprox(Eigen::Vector3f::UnitX()));
  EXPECT_EQ(back->segments[0].num_points, 12);
  EXPECT_EQ(back->timings.poses_ms, 3.5);
}

TEST(BoxesFromProtoTest, ErrorsNameTheBox) {
  v1::DetectResponse response;
  response.add_boxes()->mutable_camera_pose_box()->mutable_orientation()->set_w(1);
  response.mutable_boxes(0)->set_grasp_face(v1::BOX_FACE_PLUS_Z);
  response.add_boxes();  // zero quaternion
  absl::Status s = BoxesFromProto(response).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("boxes[1].camera_pose_box.orientation is not a rotation"));

  response.mutable_boxes(1)->mutable_camera_pose_box()->mutable_orientation()->set_w(2);
  s = BoxesFromProto(response).status();
  EXPECT_THAT(s.message(), HasSubstr("boxes[1].grasp_face 0 is not a box face"));

  response.mutable_boxes(1)->set_grasp_face(v1::BOX_FACE_MINUS_X);
  absl::StatusOr<std::vector<DetectedBox>> boxes = BoxesFromProto(response);
  ASSERT_TRUE(boxes.ok()) << boxes.status();
  ASSERT_EQ(boxes->size(), 2u);
  // A non-unit quaternion from a peer is normalised.
  EXPECT_TRUE((*boxes)[1].camera_T_box.linear().isApprox(Eigen::Matrix3d::Identity()));
  EXPECT_EQ((*boxes)[1].grasp_face, BoxFace::kMinusX);
}

TEST(PoseFromProtoTest, ConfigurationPosesNeedUnitQuaternions) {
  v1::Pose pose;
  pose.mutable_orientation()->set_w(0.5);
  absl::Status s = PoseFromProto(pose, "base_pose_camera").status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(),
              HasSubstr("base_pose_camera.orientation must be a unit quaternion (w x y z), got "
                        "norm 0.5"));
  EXPECT_TRUE(PoseFromProto(pose, "x", OrientationCheck::kNonZero).ok());

  pose.mutable_orientation()->set_w(1.0);
  pose.mutable_position()->set_y(std::numeric_limits<double>::infinity());
  s = PoseFromProto(pose, "place_pattern.origin").status();
  EXPECT_THAT(s.message(), HasSubstr("place_pattern.origin.position is not finite"));

  pose.mutable_position()->set_y(0.25);
  absl::StatusOr<Eigen::Isometry3d> T = PoseFromProto(pose, "p");
  ASSERT_TRUE(T.ok()) << T.status();
  EXPECT_EQ(T->translation().y(), 0.25);
}

TEST(BoxDimsTest, BothWays) {
  const v1::BoxDimensions proto = ToProto(BoxDims{0.3, 0.2, 0.15});
  EXPECT_EQ(proto.l(), 0.3);
  EXPECT_EQ(proto.b(), 0.2);
  EXPECT_EQ(proto.h(), 0.15);
  EXPECT_EQ(BoxDimsFromProto(proto).vec(), Eigen::Vector3d(0.3, 0.2, 0.15));
}

TEST(BoxModelsFromProtoTest, NamesAndSizesAreChecked) {
  google::protobuf::Map<std::string, v1::BoxDimensions> models;
  models["crate"] = ToProto(BoxDims{0.5, 0.4, 0.3});
  absl::StatusOr<BoxModels> ok = BoxModelsFromProto(models);
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_EQ(ok->at("crate").l, 0.5);

  models["flat"] = ToProto(BoxDims{0.5, 0.0, 0.3});
  EXPECT_THAT(BoxModelsFromProto(models).status().message(),
              HasSubstr("box_models[\"flat\"]: l, b and h must be > 0 metres"));
  models.erase("flat");
  models[""] = ToProto(BoxDims{0.5, 0.4, 0.3});
  EXPECT_THAT(BoxModelsFromProto(models).status().message(),
              HasSubstr("box_models: empty model name"));
}

TEST(ColorTest, CloudRgbRoundTrips) {
  PointCloud cloud;
  cloud.width = 2;
  cloud.height = 1;
  cloud.xyz = {{0, 0, 1}, {0.1f, 0, 1}};
  cloud.rgb = {0x00112233u, 0x00ff8000u};
  const v1::PointCloud msg = CloudToProto(cloud);
  EXPECT_EQ(msg.rgb(), std::string("\x11\x22\x33\xff\x80\x00", 6));
  absl::StatusOr<PointCloud> back = CloudFromProto(msg);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->rgb, cloud.rgb);

  // Depth only: no rgb on the wire, none back.
  cloud.rgb.clear();
  EXPECT_TRUE(CloudToProto(cloud).rgb().empty());
  EXPECT_FALSE(CloudFromProto(CloudToProto(cloud))->has_color());
}

TEST(ColorTest, CloudRgbMustBeThreeBytesPerPoint) {
  v1::PointCloud msg;
  msg.set_xyz(Pack({{0, 0, 1}, {0, 0, 2}}));
  msg.set_width(2);
  msg.set_height(1);
  msg.set_rgb("abcd");
  absl::Status s = CloudFromProto(msg).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("cloud rgb has 4 bytes; 2 points of 3 bytes need 6"));
}

TEST(ColorTest, RgbAndGreyImagesPack) {
  v1::ColorImage image;
  image.set_width(2);
  image.set_height(1);
  image.set_encoding(v1::COLOR_ENCODING_RGB8);
  image.set_data(std::string("\x01\x02\x03\xfa\xfb\xfc", 6));
  absl::StatusOr<std::vector<uint32_t>> rgb = ColorFromProto(image, 2, 1);
  ASSERT_TRUE(rgb.ok()) << rgb.status();
  EXPECT_EQ(*rgb, (std::vector<uint32_t>{0x00010203u, 0x00fafbfcu}));

  image.set_encoding(v1::COLOR_ENCODING_GRAY8);
  image.set_data(std::string("\x10\xf0", 2));
  rgb = ColorFromProto(image, 2, 1);
  ASSERT_TRUE(rgb.ok()) << rgb.status();
  EXPECT_EQ(*rgb, (std::vector<uint32_t>{0x00101010u, 0x00f0f0f0u}));
}

TEST(ColorTest, RefusalsNameTheField) {
  v1::ColorImage image;
  image.set_width(2);
  image.set_height(2);
  image.set_encoding(v1::COLOR_ENCODING_RGB8);
  image.set_data(std::string(12, '\0'));
  EXPECT_THAT(ColorFromProto(image, 4, 1).status().message(),
              HasSubstr("color is 2 x 2 but the cloud is 4 x 1"));
  image.set_data(std::string(11, '\0'));
  EXPECT_THAT(ColorFromProto(image, 2, 2).status().message(),
              HasSubstr("color data has 11 bytes; 2 x 2 pixels of 3 bytes need 12"));
  image.set_encoding(v1::COLOR_ENCODING_UNSPECIFIED);
  EXPECT_THAT(ColorFromProto(image, 2, 2).status().message(),
              HasSubstr("color encoding 0 is not COLOR_ENCODING_RGB8 or COLOR_ENCODING_GRAY8"));
}

TEST(IntrinsicsTest, BothWays) {
  CameraIntrinsics k;
  k.width = 320;
  k.fx = 300.5;
  k.cy = 119.5;
  absl::StatusOr<CameraIntrinsics> back = IntrinsicsFromProto(ToProto(k));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->width, 320);
  EXPECT_EQ(back->height, k.height);
  EXPECT_EQ(back->fx, 300.5);
  EXPECT_EQ(back->cy, 119.5);
}

}  // namespace
}  // namespace cornerpose::wire
