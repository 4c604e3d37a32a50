#include "robot_client/cell/perception_subscriber.h"

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"
#include "common/wire/box_wire.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"

namespace cornerpose::robot_client {

PerceptionSubscriber::PerceptionSubscriber(PerceptionSubscriberOptions options)
    : options_(std::move(options)) {}

PerceptionSubscriber::~PerceptionSubscriber() {
  Stop();
  if (thread_.joinable()) thread_.join();
}

void PerceptionSubscriber::Start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (started_) return;
  started_ = true;
  thread_ = std::thread([this] { Run(); });
}

void PerceptionSubscriber::Stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  stopping_ = true;
  if (context_ != nullptr) context_->TryCancel();
  changed_.notify_all();
}

bool PerceptionSubscriber::connected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connected_;
}

std::string PerceptionSubscriber::last_error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_error_;
}

uint64_t PerceptionSubscriber::frames_received() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frames_received_;
}

std::optional<FrameDetection> PerceptionSubscriber::WaitForFrameAfter(absl::Time not_before,
                                                                      absl::Duration timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto fresh = [&] { return latest_ && latest_->capture_time > not_before; };
  changed_.wait_for(lock, absl::ToChronoNanoseconds(timeout), [&] { return stopping_ || fresh(); });
  if (stopping_ || !fresh()) return std::nullopt;
  return latest_;
}

std::optional<FrameDetection> PerceptionSubscriber::WaitForFrame(const FrameFloor& floor,
                                                                 absl::Duration timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto fresh = [&] {
    return latest_ && latest_->capture_time > floor.not_before &&
           (latest_->stream != floor.stream || latest_->frame_id >= floor.min_frame_id) &&
           absl::Now() - latest_->received <= options_.max_frame_age;
  };
  changed_.wait_for(lock, absl::ToChronoNanoseconds(timeout), [&] { return stopping_ || fresh(); });
  if (stopping_ || !fresh()) return std::nullopt;
  return latest_;
}

FrameFloor PerceptionSubscriber::FloorAfterNow() const {
  std::lock_guard<std::mutex> lock(mutex_);
  FrameFloor floor;
  floor.not_before = absl::Now();
  floor.stream = stream_;
  floor.min_frame_id = latest_ && latest_->stream == stream_ ? latest_->frame_id + 2 : 0;
  return floor;
}

bool PerceptionSubscriber::SleepUnlessStopped(absl::Duration d) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, absl::ToChronoNanoseconds(d), [&] { return stopping_; });
  return !stopping_;
}

void PerceptionSubscriber::Run() {
  grpc::ChannelArguments channel_args;
  channel_args.SetMaxReceiveMessageSize(-1);
  // A reconnecting stream lands on any replica the name resolves to (a
  // headless Kubernetes Service lists each one).
  channel_args.SetLoadBalancingPolicyName("round_robin");
  // Reconnect quickly when the service comes back.
  channel_args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS,
                      static_cast<int>(absl::ToInt64Milliseconds(options_.max_backoff)));
  if (!options_.tls_server_name.empty()) {
    channel_args.SetSslTargetNameOverride(options_.tls_server_name);
  }
  std::shared_ptr<grpc::Channel> channel = grpc::CreateCustomChannel(
      options_.server,
      options_.credentials != nullptr ? options_.credentials : grpc::InsecureChannelCredentials(),
      channel_args);
  std::unique_ptr<v1::PerceptionService::Stub> stub = v1::PerceptionService::NewStub(channel);

  v1::StreamDetectionsRequest request;
  request.set_source(options_.source);
  if (options_.box) {
    *request.mutable_box() = wire::ToProto(*options_.box);
  } else {
    request.set_box_model(options_.box_model);
  }

  absl::Duration backoff = options_.initial_backoff;
  while (true) {
    grpc::ClientContext context;
    // Wait for the service to come up instead of failing at once.
    context.set_wait_for_ready(true);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
      context_ = &context;
    }
    std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
        stub->StreamDetections(&context, request);
    uint64_t stream = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stream = ++stream_;
    }
    v1::DetectResponse response;
    while (reader->Read(&response)) {
      absl::StatusOr<std::vector<DetectedBox>> boxes = wire::BoxesFromProto(response);
      std::lock_guard<std::mutex> lock(mutex_);
      if (!boxes.ok()) {
        last_error_ =
            absl::StrCat("bad detection from ", options_.server, ": ", boxes.status().message());
        continue;
      }
      latest_ = FrameDetection{
          .boxes = *std::move(boxes),
          .box_dims = response.has_box_dims_used()
                          ? std::optional<BoxDims>(wire::BoxDimsFromProto(response.box_dims_used()))
                          : std::nullopt,
          .source = response.source(),
          .source_live = response.source_live(),
          .frame_id = response.frame_id(),
          .capture_time = absl::FromUnixNanos(response.capture_time_unix_nanos()),
          .device_timestamp_us = response.device_timestamp_us(),
          .stream = stream,
          .received = absl::Now()};
      connected_ = true;
      ++frames_received_;
      backoff = options_.initial_backoff;
      changed_.notify_all();
    }
    const grpc::Status end = reader->Finish();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      context_ = nullptr;
      connected_ = false;
      // A detection from a dropped stream is not picked from later.
      latest_.reset();
      if (stopping_) return;
      last_error_ = end.ok() ? absl::StrCat("source '", options_.source, "' ended")
                             : absl::StrCat("perception stream from ", options_.server,
                                            " ended: ", end.error_message(), " (code ",
                                            static_cast<int>(end.error_code()), ")");
      changed_.notify_all();
    }
    if (!SleepUnlessStopped(backoff)) return;
    backoff = std::min(backoff * 2, options_.max_backoff);
  }
}

}  // namespace cornerpose::robot_client
