// The real server on 127.0.0.1:0, called through a real channel.
#include "server/server.h"

#include <gmock/gmock.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/impl/codegen/client_callback.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/sync_stream.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "common/perception/detector.h"
#include "common/wire/cloud_wire.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::server {
namespace {

using ::testing::HasSubstr;

// One rendered frame, shared by the tests (rendering and the in-process
// detection are the slow parts).
struct Frame {
  testing::RenderedScene scene;
  Detection expected;
};

const Frame& TheFrame() {
  static const Frame* frame = [] {
    auto* f = new Frame;
    f->scene = testing::Render(testing::MakeIsolatedScene({0.30, 0.20, 0.15}, 2, 1));
    DetectorOptions options;
    options.box = {0.30, 0.20, 0.15};
    absl::StatusOr<Detection> detection = DetectBoxes(f->scene.cloud, options);
    EXPECT_TRUE(detection.ok()) << detection.status();
    if (detection.ok()) f->expected = *std::move(detection);
    return f;
  }();
  return *frame;
}

v1::DetectRequest FrameRequest() {
  v1::DetectRequest request;
  *request.mutable_cloud() = wire::CloudToProto(TheFrame().scene.cloud);
  request.set_box_model("carton_s");
  return request;
}

class ServerTest : public ::testing::Test {
 protected:
  void Start(int max_message_bytes = ServerOptions{}.max_message_bytes, BoxModels box_models = {}) {
    ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    options.max_message_bytes = max_message_bytes;
    options.box_models = std::move(box_models);
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
    ASSERT_GT(server_->port(), 0);
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    args.SetMaxSendMessageSize(-1);
    channel_ = grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(server_->port()),
                                         grpc::InsecureChannelCredentials(), args);
    stub_ = v1::PerceptionService::NewStub(channel_);
  }

  grpc::Status Detect(const v1::DetectRequest& request, v1::DetectResponse* response,
                      std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + timeout);
    return stub_->Detect(&context, request, response);
  }

  // The server still answers: a cheap RPC and a cheap detection.
  void ExpectStillServing() {
    grpc::ClientContext context;
    v1::ListSourcesResponse sources;
    EXPECT_TRUE(stub_->ListSources(&context, v1::ListSourcesRequest(), &sources).ok());
    v1::DetectRequest empty;
    empty.mutable_cloud();
    empty.set_box_model("brick");
    v1::DetectResponse response;
    grpc::Status s = Detect(empty, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    EXPECT_EQ(response.boxes_size(), 0);
  }

  std::unique_ptr<RunningServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::PerceptionService::Stub> stub_;
};

TEST_F(ServerTest, DetectOnPackedCloudMatchesInProcessDetector) {
  Start();
  const Detection& expected = TheFrame().expected;
  ASSERT_GT(expected.boxes.size(), 0u);

  v1::DetectResponse response;
  grpc::Status s = Detect(FrameRequest(), &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  ASSERT_EQ(response.boxes_size(), static_cast<int>(expected.boxes.size()));
  EXPECT_EQ(response.segments_size(), static_cast<int>(expected.segments.size()));
  EXPECT_EQ(response.corners_size(), static_cast<int>(expected.corners.size()));
  EXPECT_EQ(response.edge_points_size(), 0);
  EXPECT_GT(response.timings().total_ms(), 0.0);
  for (int i = 0; i < response.boxes_size(); ++i) {
    const v1::DetectedBox& got = response.boxes(i);
    const DetectedBox& want = expected.boxes[i];
    const v1::Vector3& p = got.camera_pose_box().position();
    EXPECT_TRUE(
        Eigen::Vector3d(p.x(), p.y(), p.z()).isApprox(want.camera_T_box.translation(), 1e-6));
    const v1::Quaternion& o = got.camera_pose_box().orientation();
    const Eigen::Matrix3d rotation =
        Eigen::Quaterniond(o.w(), o.x(), o.y(), o.z()).toRotationMatrix();
    EXPECT_LT((rotation - want.camera_T_box.rotation()).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_NEAR(got.score(), want.score, 1e-9);
    EXPECT_NE(got.grasp_face(), v1::BOX_FACE_UNSPECIFIED);
  }

  v1::DetectRequest with_edges = FrameRequest();
  with_edges.set_include_edge_points(true);
  s = Detect(with_edges, &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(response.edge_points_size(), static_cast<int>(expected.edge_points.size()));
}

// The server alone resolves model names (its configuration first) and says
// what it used, so a client never plans with another size.
TEST_F(ServerTest, ResponseSaysWhichBoxSizeTheDetectorUsed) {
  Start(ServerOptions{}.max_message_bytes, {{"carton_s", {0.31, 0.21, 0.16}}});
  v1::DetectRequest request;
  request.mutable_cloud();  // empty: no boxes, quick
  request.set_box_model("carton_s");
  v1::DetectResponse response;
  grpc::Status s = Detect(request, &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(response.box_dims_used().l(), 0.31);
  EXPECT_EQ(response.box_dims_used().h(), 0.16);

  request.set_box_model("brick");
  ASSERT_TRUE(Detect(request, &response).ok());
  EXPECT_EQ(response.box_dims_used().l(), 0.19);
  EXPECT_EQ(response.box_dims_used().b(), 0.09);

  request.mutable_box()->set_l(0.5);
  request.mutable_box()->set_b(0.4);
  request.mutable_box()->set_h(0.3);
  ASSERT_TRUE(Detect(request, &response).ok());
  EXPECT_EQ(response.box_dims_used().b(), 0.4);
}

TEST_F(ServerTest, ColourImageIsCheckedAgainstTheDepthImage) {
  Start();
  v1::DetectRequest request;
  request.set_box_model("carton_s");
  v1::DepthImage* image = request.mutable_depth_image();
  image->set_width(2);
  image->set_height(2);
  image->set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  image->set_data(std::string(8, '\0'));
  v1::CameraIntrinsics* k = request.mutable_intrinsics();
  k->set_width(2);
  k->set_height(2);
  k->set_fx(500);
  k->set_fy(500);
  v1::ColorImage* color = request.mutable_color();
  color->set_width(3);
  color->set_height(2);
  color->set_encoding(v1::COLOR_ENCODING_GRAY8);
  color->set_data(std::string(6, '\x80'));
  v1::DetectResponse response;
  grpc::Status s = Detect(request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("color is 3 x 2 but the cloud is 2 x 2"));

  color->set_width(2);
  color->set_data(std::string(4, '\x80'));
  s = Detect(request, &response);
  EXPECT_TRUE(s.ok()) << s.error_message();

  request.set_source("anything");
  s = Detect(request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("color is for a cloud or depth_image"));
}

TEST_F(ServerTest, DetectOnUint16DepthImageFindsBoxes) {
  Start();
  const testing::RenderedScene& scene = TheFrame().scene;
  std::string data(scene.cloud.size() * 2, '\0');
  for (size_t i = 0; i < scene.cloud.size(); ++i) {
    const float z = scene.cloud.xyz[i].z();
    const uint16_t mm = std::isfinite(z) ? static_cast<uint16_t>(std::lround(z * 1000.0f)) : 0;
    std::memcpy(data.data() + 2 * i, &mm, 2);
  }
  v1::DetectRequest request;
  v1::DepthImage* image = request.mutable_depth_image();
  image->set_data(std::move(data));
  image->set_width(static_cast<uint32_t>(scene.camera.width));
  image->set_height(static_cast<uint32_t>(scene.camera.height));
  image->set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  v1::CameraIntrinsics* k = request.mutable_intrinsics();
  k->set_width(static_cast<uint32_t>(scene.camera.width));
  k->set_height(static_cast<uint32_t>(scene.camera.height));
  k->set_fx(scene.camera.fx);
  k->set_fy(scene.camera.fy);
  k->set_cx(scene.camera.cx);
  k->set_cy(scene.camera.cy);
  request.mutable_box()->set_l(0.30);
  request.mutable_box()->set_b(0.20);
  request.mutable_box()->set_h(0.15);

  v1::DetectResponse response;
  grpc::Status s = Detect(request, &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_GT(response.boxes_size(), 0);
}

TEST_F(ServerTest, BadInputGetsTheRightCodeAndTheServerKeepsServing) {
  Start();
  struct Case {
    std::string name;
    v1::DetectRequest request;
    grpc::StatusCode code;
    std::string message;
  };
  std::vector<Case> cases;
  {
    v1::DetectRequest r;
    r.mutable_cloud()->set_xyz(std::string(13, '\0'));
    r.mutable_cloud()->set_width(1);
    r.mutable_cloud()->set_height(1);
    r.set_box_model("carton_s");
    cases.push_back({"bytes not a multiple of 12", r, grpc::StatusCode::INVALID_ARGUMENT,
                     "not a multiple of 12"});
  }
  {
    v1::DetectRequest r;
    r.mutable_cloud()->set_xyz(std::string(24, '\0'));
    r.mutable_cloud()->set_width(3);
    r.mutable_cloud()->set_height(1);
    r.set_box_model("carton_s");
    cases.push_back({"width*height mismatch", r, grpc::StatusCode::INVALID_ARGUMENT,
                     "does not match its 2 points"});
  }
  {
    v1::DetectRequest r;
    r.mutable_depth_image()->set_width(2);
    r.mutable_depth_image()->set_height(2);
    r.mutable_depth_image()->set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
    r.mutable_depth_image()->set_data(std::string(8, '\0'));
    r.set_box_model("carton_s");
    cases.push_back(
        {"depth without intrinsics", r, grpc::StatusCode::INVALID_ARGUMENT, "needs intrinsics"});
  }
  {
    v1::DetectRequest r = FrameRequest();
    r.mutable_box()->set_l(0.3);
    r.mutable_box()->set_b(0.2);
    cases.push_back({"zero box size", r, grpc::StatusCode::INVALID_ARGUMENT,
                     "box size h=0 m must be positive"});
    r.mutable_box()->set_h(-0.15);
    cases.push_back({"negative box size", r, grpc::StatusCode::INVALID_ARGUMENT,
                     "box size h=-0.15 m must be positive"});
  }
  {
    v1::DetectRequest r = FrameRequest();
    r.set_box_model("crate");
    cases.push_back(
        {"unknown box model", r, grpc::StatusCode::INVALID_ARGUMENT, "unknown box model 'crate'"});
  }
  {
    v1::DetectRequest r;
    r.set_source("camera_7");
    r.set_box_model("carton_s");
    cases.push_back({"unknown source", r, grpc::StatusCode::NOT_FOUND, "unknown source"});
    // A name past gRPC's 8 KiB metadata limit came back whole in the
    // message, and the client saw RESOURCE_EXHAUSTED instead of NOT_FOUND.
    r.set_source(std::string(10000, 'x') + "\n");
    cases.push_back({"long source name", r, grpc::StatusCode::NOT_FOUND, "...' (10001 bytes)"});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    v1::DetectResponse response;
    grpc::Status s = Detect(c.request, &response);
    EXPECT_EQ(s.error_code(), c.code) << s.error_message();
    EXPECT_THAT(s.error_message(), HasSubstr(c.message));
    ExpectStillServing();
  }
}

TEST_F(ServerTest, MessageAboveTheLimitIsResourceExhausted) {
  Start(/*max_message_bytes=*/1 << 20);
  v1::DetectResponse response;
  grpc::Status s = Detect(FrameRequest(), &response);  // 3.7 MB
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
  ExpectStillServing();
}

TEST_F(ServerTest, OneMillisecondDeadlineOnAFullFrameIsExceeded) {
  Start();
  const v1::DetectRequest request = FrameRequest();
  v1::DetectResponse response;
  grpc::Status s = Detect(request, &response, std::chrono::milliseconds(1));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << s.error_message();
  ExpectStillServing();
  s = Detect(request, &response);
  EXPECT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(response.boxes_size(), static_cast<int>(TheFrame().expected.boxes.size()));
}

TEST_F(ServerTest, HealthCheckAnswersServing) {
  Start();
  auto health = grpc::health::v1::Health::NewStub(channel_);
  grpc::ClientContext context;
  grpc::health::v1::HealthCheckResponse response;
  grpc::Status s = health->Check(&context, grpc::health::v1::HealthCheckRequest(), &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST_F(ServerTest, ReflectionListsThePerceptionService) {
  Start();
  // The reflection messages are compiled into libgrpc++_reflection (Debian
  // ships no header for them): build them from its descriptors.
  namespace pb = google::protobuf;
  const pb::Descriptor* request_type = pb::DescriptorPool::generated_pool()->FindMessageTypeByName(
      "grpc.reflection.v1alpha.ServerReflectionRequest");
  const pb::Descriptor* response_type = pb::DescriptorPool::generated_pool()->FindMessageTypeByName(
      "grpc.reflection.v1alpha.ServerReflectionResponse");
  ASSERT_NE(request_type, nullptr);
  ASSERT_NE(response_type, nullptr);
  std::unique_ptr<pb::Message> request(
      pb::MessageFactory::generated_factory()->GetPrototype(request_type)->New());
  request->GetReflection()->SetString(request.get(), request_type->FindFieldByName("list_services"),
                                      "*");
  std::unique_ptr<pb::Message> response(
      pb::MessageFactory::generated_factory()->GetPrototype(response_type)->New());

  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  const grpc::internal::RpcMethod method(
      "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
      grpc::internal::RpcMethod::BIDI_STREAMING);
  std::unique_ptr<grpc::ClientReaderWriter<pb::Message, pb::Message>> stream(
      grpc::internal::ClientReaderWriterFactory<pb::Message, pb::Message>::Create(
          channel_.get(), method, &context));
  ASSERT_TRUE(stream->Write(*request));
  stream->WritesDone();
  ASSERT_TRUE(stream->Read(response.get()));
  // Drain the stream (one answer is expected) without touching `response`.
  std::unique_ptr<pb::Message> more(response->New());
  while (stream->Read(more.get())) {
  }
  grpc::Status s = stream->Finish();
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_THAT(response->DebugString(), HasSubstr("\"cornerpose.v1.PerceptionService\""));
}

}  // namespace
}  // namespace cornerpose::server
