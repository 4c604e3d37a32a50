// A real server on 127.0.0.1:0 with frame sources, and the calls the source
// tests make on it: shared by the directory-source and OpenNI2-source server
// tests.
#pragma once

#include <grpcpp/create_channel.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/server.h"

namespace cornerpose::server::testing {

class SourceServerFixture : public ::testing::Test {
 protected:
  // Starts the server (on 127.0.0.1:0) and a channel to it.
  void StartServerWith(ServerOptions options) {
    options.listen_address = "127.0.0.1:0";
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    stub_ = v1::PerceptionService::NewStub(grpc::CreateCustomChannel(
        "127.0.0.1:" + std::to_string(server_->port()), grpc::InsecureChannelCredentials(), args));
  }

  v1::ListSourcesResponse ListSources() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::ListSourcesResponse response;
    grpc::Status s = stub_->ListSources(&context, v1::ListSourcesRequest(), &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return response;
  }

  // Polls ListSources until `name` leaves STARTING (or `timeout` passes).
  v1::Source WaitForSource(const std::string& name,
                           std::chrono::seconds timeout = std::chrono::seconds(20)) {
    v1::Source found;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      const v1::ListSourcesResponse listed = ListSources();
      for (const v1::Source& source : listed.sources()) {
        if (source.name() == name) found = source;
      }
      if (found.state() != v1::SOURCE_STATE_STARTING &&
          found.state() != v1::SOURCE_STATE_UNSPECIFIED) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return found;
  }

  // Detect on the newest frame of `source`, for carton_s boxes.
  grpc::Status DetectOn(const std::string& source, v1::DetectResponse* response) {
    v1::DetectRequest request;
    request.set_source(source);
    request.set_box_model("carton_s");
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return stub_->Detect(&context, request, response);
  }

  // StreamDetections on `source` delivers `frames` responses with increasing
  // frame ids, each with boxes, and ends CANCELLED when the client cancels.
  void ExpectStreamInOrderUntilCancelled(const std::string& source, int frames) {
    v1::StreamDetectionsRequest request;
    request.set_source(source);
    request.set_box_model("carton_s");
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
        stub_->StreamDetections(&context, request);
    uint64_t last_id = 0;
    for (int i = 0; i < frames; ++i) {
      v1::DetectResponse response;
      ASSERT_TRUE(reader->Read(&response)) << "frame " << i;
      EXPECT_GT(response.frame_id(), last_id);
      last_id = response.frame_id();
      EXPECT_EQ(response.source(), source);
      EXPECT_GT(response.boxes_size(), 0);
    }
    context.TryCancel();
    v1::DetectResponse ignored;
    while (reader->Read(&ignored)) {
    }
    EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<v1::PerceptionService::Stub> stub_;
};

}  // namespace cornerpose::server::testing
