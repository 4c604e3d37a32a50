#include "tests/support/cell_sim/cell_world.h"

#include <algorithm>
#include <cmath>
#include <thread>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"

namespace cornerpose::cell_sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kTouch = 1e-6;  // resting boxes touch; they do not overlap

std::string Xyz(const Eigen::Vector3d& p) {
  return absl::StrFormat("(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
}

absl::Status OutOfRange(const char* field, double value, const char* range) {
  return absl::InvalidArgumentError(
      absl::StrCat("CellWorldOptions.", field, " is ", value, ", expected ", range));
}

}  // namespace

absl::Status CellWorldOptions::Validate() const {
  const SuctionOptions& s = suction;
  if (s.output_index < 0 || s.output_index > 7) {
    return OutOfRange("suction.output_index", s.output_index, "[0, 7]");
  }
  if (!(s.cup_radius_m > 0 && s.cup_radius_m <= 0.1)) {
    return OutOfRange("suction.cup_radius_m", s.cup_radius_m, "(0, 0.1]");
  }
  if (!(s.contact_tolerance_m > 0 && s.contact_tolerance_m <= 0.05)) {
    return OutOfRange("suction.contact_tolerance_m", s.contact_tolerance_m, "(0, 0.05]");
  }
  if (!(s.max_tilt_deg > 0 && s.max_tilt_deg <= 45)) {
    return OutOfRange("suction.max_tilt_deg", s.max_tilt_deg, "(0, 45]");
  }
  if (!(s.slip_lift_m > 0 && s.slip_lift_m < 1)) {
    return OutOfRange("suction.slip_lift_m", s.slip_lift_m, "(0, 1)");
  }
  if (!(collision.tool.radius_m > 0 && collision.tool.radius_m < 0.2)) {
    return OutOfRange("collision.tool.radius_m", collision.tool.radius_m, "(0, 0.2)");
  }
  if (!(collision.tool.cup_compliance_m >= 0 && collision.tool.cup_compliance_m < 0.1)) {
    return OutOfRange("collision.tool.cup_compliance_m", collision.tool.cup_compliance_m,
                      "[0, 0.1)");
  }
  if (!(collision.held_box_tolerance_m >= 0 && collision.held_box_tolerance_m < 0.1)) {
    return OutOfRange("collision.held_box_tolerance_m", collision.held_box_tolerance_m,
                      "[0, 0.1)");
  }
  return absl::OkStatus();
}

const char* BoxStateName(BoxState state) {
  switch (state) {
    case BoxState::kInPile:
      return "in_pile";
    case BoxState::kHeld:
      return "held";
    case BoxState::kPlaced:
      return "placed";
    case BoxState::kDropped:
      return "dropped";
  }
  return "unknown";
}

const char* PickResultName(PickResult result) {
  switch (result) {
    case PickResult::kPlaced:
      return "placed";
    case PickResult::kNothingGripped:
      return "nothing_gripped";
    case PickResult::kDropped:
      return "dropped";
    case PickResult::kCollision:
      return "collision";
    case PickResult::kInterrupted:
      return "interrupted";
    case PickResult::kNoGrasp:
      return "no_grasp";
  }
  return "unknown";
}

CellWorld::CellWorld(CellLayout layout, std::vector<testing::SceneBox> boxes,
                     CellWorldOptions options)
    : layout_(std::move(layout)), options_(std::move(options)) {
  for (const testing::SupportPart& part : layout_.supports) {
    support_obbs_.push_back({part.dims, part.world_T_part});
  }
  for (size_t i = 0; i < boxes.size(); ++i) {
    boxes_.push_back({static_cast<int>(i), boxes[i].dims, boxes[i].world_T_box,
                      BoxState::kInPile});
  }
}

testing::Scene CellWorld::CurrentScene(uint32_t noise_seed) const {
  std::lock_guard<std::mutex> lock(mutex_);
  testing::Scene scene;
  scene.camera = layout_.camera;
  scene.world_T_camera = layout_.world_T_camera;
  scene.supports = layout_.supports;
  scene.floor = true;
  scene.noise_seed = noise_seed;
  for (size_t i = 0; i < boxes_.size(); ++i) {
    if (scene.boxes.size() >= 254) break;  // the renderer's instance labels
    // The held box goes with the arm, which is not rendered either: a frame
    // taken while it rises shows the pile without it, never a box hovering
    // a centimetre above its old place (the detector would report it there).
    if (static_cast<int>(i) == held_) continue;
    scene.boxes.push_back({boxes_[i].dims, boxes_[i].world_T_box, true});
  }
  return scene;
}

uint64_t CellWorld::version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

void CellWorld::SetRenderedVersion(uint64_t version) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    rendered_version_ = std::max(rendered_version_, version);
  }
  rendered_cv_.notify_all();
}

bool CellWorld::WaitForRendered(uint64_t version, absl::Duration timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return rendered_cv_.wait_for(lock, absl::ToChronoNanoseconds(timeout),
                               [&] { return rendered_version_ >= version; });
}

std::vector<SimBox> CellWorld::Boxes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return boxes_;
}

WorldSummary CellWorld::Summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  WorldSummary s;
  s.boxes_total = static_cast<int>(boxes_.size());
  for (const SimBox& box : boxes_) {
    switch (box.state) {
      case BoxState::kInPile:
        ++s.in_pile;
        break;
      case BoxState::kHeld:
        ++s.held;
        break;
      case BoxState::kPlaced:
        ++s.placed;
        break;
      case BoxState::kDropped:
        ++s.dropped;
        break;
    }
  }
  s.collisions = collisions_;
  s.picks = picks_;
  return s;
}

void CellWorld::SetPickListener(
    std::function<void(const PickEvent&, const WorldSummary&)> listener) {
  std::lock_guard<std::mutex> lock(mutex_);
  listener_ = std::move(listener);
}

Eigen::Isometry3d CellWorld::WorldTcp(const ur_emulator::ArmState& state) const {
  return layout_.world_T_base * state.base_T_tcp;
}

bool CellWorld::VacuumOn(const ur_emulator::ArmState& state) const {
  const uint32_t bits = options_.suction.tool_output ? state.tool_outputs : state.standard_outputs;
  return ((bits >> options_.suction.output_index) & 1u) != 0;
}

bool CellWorld::FreeLocked(int i, const Obb& pose) const {
  if (LowestZ(pose) < -kTouch) return false;
  for (const Obb& support : support_obbs_) {
    if (BoxesOverlap(pose, support, kTouch)) return false;
  }
  for (const SimBox& other : boxes_) {
    if (other.id == i || other.state == BoxState::kHeld) continue;
    if (BoxesOverlap(pose, {other.dims, other.world_T_box}, kTouch)) return false;
  }
  return true;
}

void CellWorld::SettleLocked(int i) {
  SimBox& box = boxes_[static_cast<size_t>(i)];
  Obb pose{box.dims, box.world_T_box};
  // Pressed into what is under it (the cup yields): back up first.
  for (int k = 0; k < 60 && !FreeLocked(i, pose); ++k) {
    pose.world_T_box.translation().z() += 0.001;
  }
  // Then fall: 4 mm steps, and bisection on the first step that hits.
  const double start_z = pose.world_T_box.translation().z();
  double free_drop = 0.0;
  for (double drop = 0.004;; drop += 0.004) {
    Obb trial = pose;
    trial.world_T_box.translation().z() = start_z - drop;
    if (FreeLocked(i, trial)) {
      free_drop = drop;
      continue;
    }
    double hit = drop;
    for (int it = 0; it < 25; ++it) {
      const double mid = 0.5 * (free_drop + hit);
      trial.world_T_box.translation().z() = start_z - mid;
      (FreeLocked(i, trial) ? free_drop : hit) = mid;
    }
    break;
  }
  box.world_T_box = pose.world_T_box;
  box.world_T_box.translation().z() = start_z - free_drop;
}

void CellWorld::GripLocked(const ur_emulator::ArmState& state) {
  const Eigen::Isometry3d tcp = WorldTcp(state);
  const Eigen::Vector3d tool_z = tcp.linear().col(2);
  const SuctionOptions& s = options_.suction;
  // The face under the cup: its plane within the contact tolerance of the
  // cup's centre, the centre inside the face, the tool along its inward
  // normal; the nearest such face.
  int best = -1;
  double best_distance = 1e9;
  bool best_sealed = false;
  double best_overhang = 0.0;
  for (const SimBox& box : boxes_) {
    if (box.state == BoxState::kHeld) continue;
    const Eigen::Vector3d p = box.world_T_box.inverse() * tcp.translation();
    const Eigen::Vector3d half = 0.5 * box.dims.vec();
    for (int axis = 0; axis < 3; ++axis) {
      for (double sign : {-1.0, 1.0}) {
        const double distance = std::abs(sign * p[axis] - half[axis]);
        if (distance > s.contact_tolerance_m) continue;
        const Eigen::Vector3d inward = -sign * box.world_T_box.linear().col(axis);
        if (std::acos(std::clamp(tool_z.dot(inward), -1.0, 1.0)) > s.max_tilt_deg * kDeg) continue;
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        if (std::abs(p[u]) > half[u] || std::abs(p[v]) > half[v]) continue;
        if (distance < best_distance) {
          best = box.id;
          best_distance = distance;
          best_overhang = std::max(std::abs(p[u]) + s.cup_radius_m - half[u],
                                   std::abs(p[v]) + s.cup_radius_m - half[v]);
          best_sealed = best_overhang <= 0.0;
        }
      }
    }
  }
  if (best < 0) {
    if (current_) {
      current_->result = PickResult::kNothingGripped;
      current_->detail = absl::StrCat("no box face under the cup at ", Xyz(tcp.translation()));
    }
    return;
  }
  SimBox& box = boxes_[static_cast<size_t>(best)];
  if (current_) current_->box_id = best;
  // Another box resting on it (or wedged over it) keeps it down.
  Obb lifted{box.dims, box.world_T_box};
  lifted.world_T_box.translation().z() += 0.005;
  for (const SimBox& other : boxes_) {
    if (other.id == best || other.state == BoxState::kHeld) continue;
    if (BoxesOverlap(lifted, {other.dims, other.world_T_box}, 1e-4)) {
      if (current_) {
        current_->result = PickResult::kNothingGripped;
        current_->detail = absl::StrCat("box ", best, " cannot be lifted: box ", other.id,
                                        " lies on it");
      }
      return;
    }
  }
  held_ = best;
  held_moved_ = false;
  grip_box_position_ = box.world_T_box.translation();
  held_badly_ = !best_sealed;
  grip_tcp_z_ = tcp.translation().z();
  tcp_T_held_ = tcp.inverse() * box.world_T_box;
  box.state = BoxState::kHeld;
  if (current_) {
    current_->result = PickResult::kPlaced;  // until it is set down elsewhere or lost
    current_->detail =
        best_sealed ? absl::StrCat("gripped box ", best)
                    : absl::StrFormat("gripped box %d badly: the cup reaches %.0f mm past its face",
                                      best, 1000 * best_overhang);
  }
}

void CellWorld::ReleaseLocked(const Eigen::Isometry3d& tcp) {
  const int i = held_;
  held_ = -1;
  SimBox& box = boxes_[static_cast<size_t>(i)];
  const double before = box.world_T_box.translation().z();
  SettleLocked(i);
  const Eigen::Vector3d centre = box.world_T_box.translation();
  const double fall = before - centre.z();
  if (layout_.place_area.Contains(centre)) {
    box.state = BoxState::kPlaced;
    // Let go well above where it lands (the box was taken for another size
    // or orientation): it reached the place area, but dropped.
    if (current_ && current_->result == PickResult::kPlaced && fall > options_.max_set_down_fall_m) {
      current_->result = PickResult::kDropped;
      current_->detail += absl::StrFormat("; let go %.0f mm above the place area and fell onto it",
                                          1000 * fall);
    }
    ChangedLocked();
    return;
  }
  box.state = layout_.pick_area.Contains(centre) ? BoxState::kInPile : BoxState::kDropped;
  if (current_ && current_->result == PickResult::kPlaced) {
    current_->result = PickResult::kDropped;
    current_->detail = absl::StrCat("box ", i, " let go at ", Xyz(tcp.translation()),
                                    ", outside the place area; it came to rest at ",
                                    Xyz(centre));
  }
  ChangedLocked();
}

std::optional<std::string> CellWorld::ContactLocked(const ur_emulator::ArmState& state) const {
  std::vector<Capsule> capsules =
      ArmCapsules(layout_.arm, state.joints, state.flange_T_tcp, options_.collision.tool);
  for (Capsule& c : capsules) {
    c.a = layout_.world_T_base * c.a;
    c.b = layout_.world_T_base * c.b;
  }
  for (const Capsule& c : capsules) {
    if (std::min(c.a.z(), c.b.z()) - c.radius < 0.0) return absl::StrCat(c.name, " touched the floor");
    for (size_t k = 0; k < support_obbs_.size(); ++k) {
      if (CapsuleTouchesBox(c, support_obbs_[k])) {
        return absl::StrCat(c.name, " touched the ", layout_.supports[k].name);
      }
    }
    for (const SimBox& box : boxes_) {
      if (box.state == BoxState::kHeld) continue;
      if (CapsuleTouchesBox(c, {box.dims, box.world_T_box})) {
        return absl::StrCat(c.name, " touched box ", box.id, " at ",
                            Xyz(box.world_T_box.translation()));
      }
    }
  }
  if (held_ >= 0) {
    const SimBox& held = boxes_[static_cast<size_t>(held_)];
    const Obb obb{held.dims, held.world_T_box};
    const double tol = options_.collision.held_box_tolerance_m;
    if (LowestZ(obb) < -tol) return absl::StrCat("the held box ", held.id, " touched the floor");
    for (size_t k = 0; k < support_obbs_.size(); ++k) {
      if (BoxesOverlap(obb, support_obbs_[k], tol)) {
        return absl::StrCat("the held box ", held.id, " hit the ", layout_.supports[k].name);
      }
    }
    for (const SimBox& box : boxes_) {
      if (box.id == held.id || box.state == BoxState::kHeld) continue;
      if (BoxesOverlap(obb, {box.dims, box.world_T_box}, tol)) {
        return absl::StrCat("the held box ", held.id, " hit box ", box.id, " at ",
                            Xyz(box.world_T_box.translation()));
      }
    }
  }
  return std::nullopt;
}

std::optional<std::string> CellWorld::OnStep(const ur_emulator::ArmState& state) {
  std::lock_guard<std::mutex> lock(mutex_);
  const Eigen::Isometry3d tcp = WorldTcp(state);
  if (held_ >= 0) {
    SimBox& box = boxes_[static_cast<size_t>(held_)];
    box.world_T_box = tcp * tcp_T_held_;
    // The camera needs a new frame once the box has left its place (and
    // again when it is set down), not at every step of the way.
    if (!held_moved_ && (box.world_T_box.translation() - grip_box_position_).norm() > 0.01) {
      held_moved_ = true;
      ChangedLocked();
    }
    if (held_badly_ && tcp.translation().z() - grip_tcp_z_ > options_.suction.slip_lift_m) {
      const int lost = held_;
      held_ = -1;
      SettleLocked(lost);
      ChangedLocked();
      box.state = layout_.pick_area.Contains(box.world_T_box.translation()) ? BoxState::kInPile
                                                                            : BoxState::kDropped;
      if (current_) {
        current_->result = PickResult::kDropped;
        current_->detail += "; it slipped off the cup on the way up and fell back";
      }
    }
  }
  if (!options_.collision.enabled) return std::nullopt;
  std::optional<std::string> contact = ContactLocked(state);
  if (contact) {
    *contact += absl::StrFormat(" (joints %.3f %.3f %.3f %.3f %.3f %.3f)", state.joints[0],
                                state.joints[1], state.joints[2], state.joints[3],
                                state.joints[4], state.joints[5]);
    ++collisions_;
    if (current_) {
      current_->result = PickResult::kCollision;
      current_->detail = *contact;
    }
  }
  return contact;
}

void CellWorld::OnOutputs(const ur_emulator::ArmState& state) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool on = VacuumOn(state);
  if (on && !vacuum_) GripLocked(state);
  if (!on && vacuum_ && held_ >= 0) ReleaseLocked(WorldTcp(state));
  vacuum_ = on;
}

void CellWorld::OnProgramStart(const std::string& program, double time_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  PickEvent event;
  event.program = program;
  event.start_time_s = time_s;
  if (last_end_wall_) event.wait_before_s = absl::ToDoubleSeconds(absl::Now() - *last_end_wall_);
  current_ = event;
}

void CellWorld::OnProgramEnd(const std::string& program, bool completed, double time_s) {
  uint64_t version;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (current_ && current_->program == program) {
      current_->end_time_s = time_s;
      if (!completed && (current_->result == PickResult::kNoGrasp ||
                         (current_->result == PickResult::kPlaced && held_ >= 0))) {
        current_->result = PickResult::kInterrupted;
        current_->detail += current_->detail.empty() ? "the program ended early"
                                                     : "; the program ended early";
      }
    }
    version = version_;
  }
  bool camera = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    camera = rendered_version_ > 0;  // a camera follows this world
  }
  if (camera) {
    WaitForRendered(version, options_.camera_sync_timeout);
    std::this_thread::sleep_for(absl::ToChronoNanoseconds(options_.frame_settle));
  }
  std::function<void(const PickEvent&, const WorldSummary&)> listener;
  std::optional<PickEvent> event;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_end_wall_ = absl::Now();
    if (current_ && current_->program == program) {
      event = *current_;
      picks_.push_back(*current_);
      current_.reset();
    }
    listener = listener_;
  }
  if (event && listener) listener(*event, Summary());
}

}  // namespace cornerpose::cell_sim
