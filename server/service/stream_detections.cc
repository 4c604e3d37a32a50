#include "server/service/stream_detections.h"

#include <utility>

#include "absl/time/clock.h"
#include "server/service/status_mapping.h"

namespace cornerpose::server {
namespace {

// How often a stream waiting for a frame checks for cancel and shutdown.
constexpr absl::Duration kPollPeriod = absl::Milliseconds(100);

}  // namespace

StreamDetectionsReactor::StreamDetectionsReactor(const grpc::Status& error) { Finish(error); }

StreamDetectionsReactor::StreamDetectionsReactor(DetectionPool* pool, SharedDetections* shared,
                                                 std::string share_key, FrameSource* source,
                                                 DetectorOptions options, ResponseContents contents,
                                                 bool every_frame,
                                                 const std::atomic<bool>* stopping,
                                                 std::atomic<int>* open_streams)
    : pool_(pool),
      shared_(shared),
      share_key_(std::move(share_key)),
      source_(source),
      options_(std::move(options)),
      contents_(contents),
      every_frame_(every_frame),
      stopping_(stopping),
      open_streams_(open_streams) {
  thread_ = std::thread([this] { Run(); });
}

void StreamDetectionsReactor::OnWriteDone(bool ok) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    write_pending_ = false;
    write_ok_ = ok;
  }
  changed_.notify_all();
}

void StreamDetectionsReactor::OnCancel() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
  }
  changed_.notify_all();
}

void StreamDetectionsReactor::OnDone() {
  // Finish is Run's last act, but OnDone may run inside it on that thread.
  if (thread_.joinable()) {
    if (thread_.get_id() == std::this_thread::get_id()) {
      thread_.detach();
    } else {
      thread_.join();
    }
  }
  // Last, so a server waiting for its streams to end sees none still
  // touching the service.
  std::atomic<int>* open_streams = open_streams_;
  delete this;
  if (open_streams != nullptr) open_streams->fetch_sub(1);
}

grpc::Status StreamDetectionsReactor::ShouldStop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (cancelled_) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
  if (!write_ok_) return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  if (stopping_->load()) {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
  }
  return grpc::Status::OK;
}

void StreamDetectionsReactor::Run() {
  uint64_t last_id = 0;
  grpc::Status end;
  while ((end = ShouldStop()).ok()) {
    absl::StatusOr<Frame> frame = every_frame_ ? source_->GrabAfter(last_id, kPollPeriod)
                                               : source_->GrabNewerThan(last_id, kPollPeriod);
    if (!frame.ok()) {
      if (frame.status().code() == absl::StatusCode::kOutOfRange) break;  // played once: done
      if (source_->state().state == SourceState::kFailed) {
        end = ToGrpcStatus(frame.status());
        break;
      }
      continue;  // no new frame yet
    }
    last_id = frame->id;

    // Held until the next frame's, so a stream a frame behind still finds
    // this one to share.
    current_ = shared_->Get(share_key_, *std::move(frame), options_, pool_);
    const absl::StatusOr<Detection>& result = current_->result.get();
    if (!result.ok()) {
      end = ToGrpcStatus(result.status());
      break;
    }
    response_ = MakeDetectResponse(*result, current_->options, current_->frame.get(), contents_);
    response_.set_detected_frame_id(current_->detected_frame_id);

    std::unique_lock<std::mutex> lock(mutex_);
    write_pending_ = true;
    lock.unlock();
    StartWrite(&response_);
    // gRPC calls OnWriteDone for every write, also after a cancel.
    lock.lock();
    changed_.wait(lock, [&] { return !write_pending_; });
  }
  Finish(end);
}

}  // namespace cornerpose::server
