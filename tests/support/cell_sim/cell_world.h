// The simulated cell that the emulated arm and the simulated camera share:
// rigid boxes (a pallet load, a heap, a bin), the fixed parts (pallets, the
// robot's pedestal, bin walls), the place area and the camera. As the
// emulator's ArmWorld it grips with suction, carries, sets down and drops
// boxes and reports contact of the arm or the held box as a collision
// (protective stop); it keeps a record of every pick for the demo's
// figures. Thread-safe.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "tests/support/cell_sim/geometry.h"
#include "tests/support/scene_generator.h"
#include "tests/support/ur_emulator/arm_world.h"

namespace cornerpose::cell_sim {

// The cell's fixed geometry, in the world frame (z up, floor at z = 0).
struct CellLayout {
  Eigen::Isometry3d world_T_base = Eigen::Isometry3d::Identity();  // the robot's base frame
  ur::ArmModel arm = ur::ArmModel::kUr5e;
  CameraIntrinsics camera;
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  std::vector<testing::SupportPart> supports;  // pallets, pedestal, bin: rendered and solid
  Aabb pick_area;   // where the boxes start; a box whose centre stays in it is "left"
  Aabb place_area;  // a box set down with its centre in it is "placed"
};

struct SuctionOptions {
  // Which output drives the vacuum: tool digital output n (true) or
  // standard digital output n (false); n in [0, 7].
  bool tool_output = true;
  int output_index = 0;
  // Radius of the cup's seal, m, (0, 0.1]: the whole disc must lie on one
  // face for a good grip; a cup over an edge or a seam grips badly.
  double cup_radius_m = 0.02;
  // The cup's centre must lie within this of the face's plane, m, (0, 0.05].
  double contact_tolerance_m = 0.01;
  // The tool's axis must lie within this of the face's inward normal,
  // degrees, (0, 45].
  double max_tilt_deg = 5.0;
  // A bad grip lets go once the tool has risen this far, m, > 0.
  double slip_lift_m = 0.02;
};

struct CollisionOptions {
  bool enabled = true;
  ToolShape tool;
  // The held box may press this far into what it touches (the cup yields),
  // m, >= 0; deeper is a collision.
  double held_box_tolerance_m = 0.01;
};

struct CellWorldOptions {
  SuctionOptions suction;
  CollisionOptions collision;
  // How long a program's end waits for the camera to show the current
  // world, wall time; then it waits `frame_settle` more, so a frame
  // source polling the camera's directory has picked the new frame up.
  absl::Duration camera_sync_timeout = absl::Seconds(10);
  absl::Duration frame_settle = absl::Milliseconds(150);
  // A box let go higher than this above where it comes to rest was dropped,
  // not set down, m, >= 0.
  double max_set_down_fall_m = 0.02;

  absl::Status Validate() const;
};

enum class BoxState { kInPile, kHeld, kPlaced, kDropped };
const char* BoxStateName(BoxState state);

struct SimBox {
  int id = 0;
  BoxDims dims;
  Eigen::Isometry3d world_T_box = Eigen::Isometry3d::Identity();
  BoxState state = BoxState::kInPile;
};

// What one program did to the world.
enum class PickResult {
  kPlaced,          // gripped, carried and set down in the place area
  kNothingGripped,  // vacuum on with no face under the cup, or the box pinned under another
  kDropped,         // gripped badly and lost on the way, or let go outside the place area
  kCollision,       // the arm or the held box hit something (protective stop)
  kInterrupted,     // the program ended early otherwise (stop, protective stop, error)
  kNoGrasp,         // the program never switched the vacuum on
};
const char* PickResultName(PickResult result);

struct PickEvent {
  std::string program;
  PickResult result = PickResult::kNoGrasp;
  int box_id = -1;     // the box gripped (or tried), -1 none
  std::string detail;  // e.g. "cup over an edge of box 3", "wrist_2 touched box 7"
  double start_time_s = 0.0;  // simulated
  double end_time_s = 0.0;
  // Wall seconds from the end of the previous program (once the camera
  // showed its result) to this one's start: the cell's perception and
  // planning time; 0 for the first program.
  double wait_before_s = 0.0;
};

struct WorldSummary {
  int boxes_total = 0;
  int in_pile = 0;
  int placed = 0;
  int dropped = 0;
  int held = 0;
  int collisions = 0;
  std::vector<PickEvent> picks;
};

class CellWorld final : public ur_emulator::ArmWorld {
 public:
  // Boxes must not interpenetrate each other or the supports.
  CellWorld(CellLayout layout, std::vector<testing::SceneBox> boxes, CellWorldOptions options);

  const CellLayout& layout() const { return layout_; }

  // The scene as the camera sees it now (every box, every support), with
  // noise seed `noise_seed`; and a counter that changes with every change.
  testing::Scene CurrentScene(uint32_t noise_seed) const;
  uint64_t version() const;
  // The camera reports the world version its newest frame shows.
  void SetRenderedVersion(uint64_t version);
  // Waits until the camera shows version >= `version`; false on timeout.
  bool WaitForRendered(uint64_t version, absl::Duration timeout) const;

  std::vector<SimBox> Boxes() const;
  WorldSummary Summary() const;
  // Called once per finished program, after the camera caught up.
  void SetPickListener(std::function<void(const PickEvent&, const WorldSummary&)> listener);

  // ur_emulator::ArmWorld
  std::optional<std::string> OnStep(const ur_emulator::ArmState& state) override;
  void OnOutputs(const ur_emulator::ArmState& state) override;
  void OnProgramStart(const std::string& program, double time_s) override;
  void OnProgramEnd(const std::string& program, bool completed, double time_s) override;

 private:
  bool VacuumOn(const ur_emulator::ArmState& state) const;
  void GripLocked(const ur_emulator::ArmState& state);
  void ReleaseLocked(const Eigen::Isometry3d& world_T_tcp);
  // Lets box i fall straight down until it rests on something.
  void SettleLocked(int i);
  bool FreeLocked(int i, const Obb& pose) const;
  std::optional<std::string> ContactLocked(const ur_emulator::ArmState& state) const;
  Eigen::Isometry3d WorldTcp(const ur_emulator::ArmState& state) const;
  void ChangedLocked() { ++version_; }

  const CellLayout layout_;
  const CellWorldOptions options_;
  std::vector<Obb> support_obbs_;

  mutable std::mutex mutex_;
  mutable std::condition_variable rendered_cv_;
  std::vector<SimBox> boxes_;
  uint64_t version_ = 1;
  uint64_t rendered_version_ = 0;
  bool vacuum_ = false;
  int held_ = -1;
  bool held_badly_ = false;
  bool held_moved_ = false;
  Eigen::Vector3d grip_box_position_ = Eigen::Vector3d::Zero();
  double grip_tcp_z_ = 0.0;
  Eigen::Isometry3d tcp_T_held_ = Eigen::Isometry3d::Identity();
  int collisions_ = 0;
  std::optional<PickEvent> current_;
  std::vector<PickEvent> picks_;
  std::optional<absl::Time> last_end_wall_;
  std::function<void(const PickEvent&, const WorldSummary&)> listener_;
};

}  // namespace cornerpose::cell_sim
