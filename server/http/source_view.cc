#include "server/http/source_view.h"

#include <future>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"

namespace cornerpose::server {
namespace {

// How long the thread waits for a frame before looking at the boxes again.
constexpr absl::Duration kPollPeriod = absl::Milliseconds(100);
// The window of the frame rate.
constexpr absl::Duration kRateWindow = absl::Seconds(5);
// Boxes watched at once per source; each costs a detection per frame.
constexpr size_t kMaxBoxes = 8;

}  // namespace

SourceView::SourceView(FrameSource* source, DetectionPool* pool, DetectorOptions defaults,
                       const BoxModels* box_models, HttpOptions options, DetectionHook hook)
    : source_(source),
      pool_(pool),
      defaults_(std::move(defaults)),
      box_models_(box_models),
      options_(std::move(options)),
      hook_(std::move(hook)) {
  thread_ = std::thread([this] { Run(); });
}

SourceView::~SourceView() { Stop(); }

void SourceView::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

SourceSummary SourceView::Summary() const {
  SourceSummary out;
  out.name = source_->name();
  out.description = source_->description();
  out.status = source_->state();
  out.box_label = options_.view_box;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!frames_.empty()) {
    out.frame_id = frames_.back()->id;
    out.frame_age_s = absl::ToDoubleSeconds(absl::Now() - frames_.back()->capture_time);
  }
  const absl::Time now = absl::Now();
  int recent = 0;
  absl::Time first = now;
  for (absl::Time t : arrivals_) {
    if (now - t > kRateWindow) continue;
    if (recent == 0) first = t;
    ++recent;
  }
  // n arrivals span n - 1 intervals; the time since the last one counts
  // too, so a source that stopped decays to 0.
  if (recent >= 2) out.fps = (recent - 1) / absl::ToDoubleSeconds(now - first);
  out.detection_ms = last_detection_ms_;
  return out;
}

absl::StatusOr<SourceView::BoxState*> SourceView::BoxLocked(const std::string& box) {
  const std::string label = Label(box);
  auto it = boxes_.find(label);
  if (it != boxes_.end()) return &it->second;
  absl::StatusOr<BoxDims> dims = ResolveBoxModel(label, *box_models_);
  if (!dims.ok()) dims = ParseBoxDims(label);
  if (!dims.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("box '", label, "' is neither a box model nor L,B,H in metres"));
  }
  if (boxes_.size() >= kMaxBoxes) {
    // Forget a box nobody watches any more before refusing.
    const absl::Time now = absl::Now();
    for (auto b = boxes_.begin(); b != boxes_.end(); ++b) {
      if (b->second.watchers == 0 &&
          now - b->second.last_interest > absl::Seconds(options_.view_idle_s)) {
        boxes_.erase(b);
        break;
      }
    }
    if (boxes_.size() >= kMaxBoxes) {
      return absl::ResourceExhaustedError(
          absl::StrCat("source '", name(), "': ", kMaxBoxes, " boxes are watched already"));
    }
  }
  BoxState state;
  state.options = defaults_;
  state.options.box = *dims;
  return &boxes_.emplace(label, std::move(state)).first->second;
}

absl::Status SourceView::Watch(const std::string& box, int delta) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    absl::StatusOr<BoxState*> state = BoxLocked(box);
    if (!state.ok()) return state.status();
    (*state)->watchers += delta;
    (*state)->last_interest = absl::Now();
  }
  changed_.notify_all();
  return absl::OkStatus();
}

absl::StatusOr<std::shared_ptr<const ViewDetection>> SourceView::NextDetection(
    const std::string& box, uint64_t after_id, absl::Duration timeout) {
  const absl::Time deadline = absl::Now() + timeout;
  std::unique_lock<std::mutex> lock(mutex_);
  absl::StatusOr<BoxState*> found = BoxLocked(box);
  if (!found.ok()) return found.status();
  BoxState* state = *found;
  for (;;) {
    state->last_interest = absl::Now();
    if (state->latest != nullptr && state->latest->frame->id > after_id) return state->latest;
    if (stopping_) return absl::UnavailableError("the server is shutting down");
    const SourceStatus status = source_->state();
    if (status.state == SourceState::kFailed) {
      return absl::UnavailableError(absl::StrCat("source '", name(), "' failed: ", status.reason));
    }
    const absl::Time now = absl::Now();
    if (now >= deadline) {
      if (!state->error.ok()) return state->error;
      return absl::UnavailableError(absl::StrCat("source '", name(), "': no ",
                                                 after_id == 0 ? "frame" : "newer frame",
                                                 " yet"));
    }
    changed_.notify_all();  // the thread may be waiting for a box to watch
    // Bounded waits: the source's state is not signalled here.
    changed_.wait_for(lock, absl::ToChronoNanoseconds(
                                std::min(deadline - now, absl::Milliseconds(200))));
  }
}

std::shared_ptr<const Frame> SourceView::FindFrame(uint64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& frame : frames_) {
    if (frame->id == id) return frame;
  }
  return nullptr;
}

void SourceView::Run() {
  uint64_t last_id = 0;
  const absl::Duration min_period = absl::Seconds(1.0 / options_.view_max_rate_hz);
  const absl::Duration idle = absl::Seconds(options_.view_idle_s);
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
    }
    absl::StatusOr<Frame> grabbed = source_->GrabNewerThan(last_id, kPollPeriod);
    std::shared_ptr<const Frame> newest;
    // One box to detect for this turn: the one waiting longest.
    std::string label;
    DetectorOptions options;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (grabbed.ok()) {
        last_id = grabbed->id;
        frames_.push_back(std::make_shared<const Frame>(*std::move(grabbed)));
        while (static_cast<int>(frames_.size()) > options_.frames_kept) frames_.pop_front();
        const absl::Time now = absl::Now();
        arrivals_.push_back(now);
        while (!arrivals_.empty() && now - arrivals_.front() > kRateWindow) arrivals_.pop_front();
      } else if (source_->state().state != SourceState::kRunning) {
        // Failed or finished: GrabNewerThan returns at once, so wait here
        // (a page asking for a new box wakes this).
        changed_.wait_for(lock, absl::ToChronoNanoseconds(kPollPeriod));
      }
      if (frames_.empty()) continue;
      newest = frames_.back();
      const absl::Time now = absl::Now();
      absl::Time oldest_run = absl::InfiniteFuture();
      for (auto& [name, state] : boxes_) {
        const bool watched = state.watchers > 0 || now - state.last_interest < idle;
        const bool stale = state.latest == nullptr || state.latest->frame->id < newest->id;
        if (watched && stale && now - state.last_run >= min_period && state.last_run < oldest_run) {
          oldest_run = state.last_run;
          label = name;
          options = state.options;
        }
      }
      if (label.empty()) continue;
      boxes_[label].last_run = now;
    }

    UseFrameCamera(newest->camera, &options);
    std::promise<absl::StatusOr<Detection>> done;
    std::future<absl::StatusOr<Detection>> result = done.get_future();
    pool_->Submit([&] { done.set_value(DetectBoxes(newest->cloud, options)); });
    absl::StatusOr<Detection> detection = result.get();
    if (detection.ok() && hook_) hook_(*detection);

    std::lock_guard<std::mutex> lock(mutex_);
    auto it = boxes_.find(label);
    if (it == boxes_.end()) continue;  // forgotten meanwhile
    if (detection.ok()) {
      last_detection_ms_ = detection->timings.total_ms;
      auto view = std::make_shared<ViewDetection>();
      view->frame = newest;
      view->detection = *std::move(detection);
      view->box_label = label;
      view->options = options;
      it->second.latest = std::move(view);
      it->second.error = absl::OkStatus();
    } else {
      it->second.error = detection.status();
    }
    changed_.notify_all();
  }
}

}  // namespace cornerpose::server
