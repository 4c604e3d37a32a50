#include "tests/support/cell_sim/sim_cell.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"
#include "tests/support/obb.h"

namespace cornerpose::cell_sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

absl::Status Bad(const std::string& field, double value, const char* range) {
  return absl::InvalidArgumentError(absl::StrCat(field, " is ", value, ", expected ", range));
}

Eigen::Isometry3d At(const Eigen::Vector3d& t, double yaw = 0.0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() = t;
  return pose;
}

bool Overlaps(const testing::SceneBox& a, const std::vector<testing::SceneBox>& placed) {
  for (const auto& b : placed) {
    if (testing::ObbSeparation(a.dims, a.world_T_box, b.dims, b.world_T_box) < -1e-9) return true;
  }
  return false;
}

// Layers of boxes on the pallet deck, each layer centred.
std::vector<testing::SceneBox> PalletLoad(const SimCellOptions& cell, const SimLoadOptions& load,
                                          int* per_layer_max) {
  std::mt19937 rng(load.seed);
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3), turn(-0.3 * kDeg, 0.3 * kDeg);
  std::vector<testing::SceneBox> boxes;
  const BoxDims& d = load.box;
  *per_layer_max = 0;
  for (int layer = 0; layer < load.layers; ++layer) {
    const bool turned = load.pattern == "interlock" && layer % 2 == 1;
    const double along_x = turned ? d.b : d.l, along_y = turned ? d.l : d.b;
    const int cols =
        static_cast<int>((cell.pick_length_m + load.gap_m) / (along_x + load.gap_m) + 1e-6);
    const int rows =
        static_cast<int>((cell.pick_width_m + load.gap_m) / (along_y + load.gap_m) + 1e-6);
    *per_layer_max = std::max(*per_layer_max, cols * rows);
    const double z = testing::kEurPalletHeight + (layer + 0.5) * d.h;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const Eigen::Vector3d nominal((c - 0.5 * (cols - 1)) * (along_x + load.gap_m),
                                      (r - 0.5 * (rows - 1)) * (along_y + load.gap_m), z);
        testing::SceneBox box;
        box.dims = d;
        // One draw at a time: argument order is the compiler's choice (g++
        // goes right to left, and these are the draws it has always made).
        const double yaw = turn(rng);
        const double dy = jitter(rng);
        const double dx = jitter(rng);
        box.world_T_box =
            At(nominal + Eigen::Vector3d(dx, dy, 0), (turned ? 0.5 * M_PI : 0.0) + yaw);
        if (!Overlaps(box, boxes)) boxes.push_back(box);  // defensive: never interpenetrate
      }
    }
  }
  return boxes;
}

// A heap from the scene generator, moved onto the pallet deck (or the bin's
// floor at deck_z); the first layout (of up to 500 seeds) that fits the area.
absl::StatusOr<std::vector<testing::SceneBox>> HeapLoad(const SimCellOptions& cell,
                                                        const SimLoadOptions& load, double deck_z,
                                                        double margin_m) {
  for (uint32_t attempt = 0; attempt < 500; ++attempt) {
    const testing::Scene heap =
        testing::MakeHeapScene(load.box, load.heap_boxes, load.seed + 7919u * attempt);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (const auto& b : heap.boxes) {
      for (const Eigen::Vector3d& p : testing::BoxCorners(b.dims, b.world_T_box)) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
    const Eigen::Vector3d size = hi - lo;
    if (size.x() > cell.pick_length_m - 2 * margin_m ||
        size.y() > cell.heap_width_m - 2 * margin_m) {
      continue;
    }
    const Eigen::Vector3d shift(-0.5 * (lo.x() + hi.x()), -0.5 * (lo.y() + hi.y()), deck_z);
    std::vector<testing::SceneBox> boxes = heap.boxes;
    for (auto& b : boxes) b.world_T_box.pretranslate(shift);
    return boxes;
  }
  return absl::InvalidArgumentError(
      absl::StrCat("no heap of ", load.heap_boxes,
                   " boxes of this size fits the pick area (in 500 layouts); try fewer boxes"));
}

// A bin standing on the pallet deck: a floor and four walls around the area.
std::vector<testing::SupportPart> Bin(const SimCellOptions& cell, double wall_height_m) {
  const double t = 0.02, floor_top = testing::kEurPalletHeight + t;
  const double L = cell.pick_length_m + 2 * t, W = cell.heap_width_m + 2 * t;
  const double z_wall = floor_top + 0.5 * wall_height_m;
  return {
      {"bin_floor", {L, W, t}, At({0, 0, testing::kEurPalletHeight + 0.5 * t})},
      {"bin_wall", {L, t, wall_height_m}, At({0, 0.5 * (W - t), z_wall})},
      {"bin_wall", {L, t, wall_height_m}, At({0, -0.5 * (W - t), z_wall})},
      {"bin_wall", {t, W - 2 * t, wall_height_m}, At({0.5 * (L - t), 0, z_wall})},
      {"bin_wall", {t, W - 2 * t, wall_height_m}, At({-0.5 * (L - t), 0, z_wall})},
  };
}

std::string Num(double v) { return absl::StrFormat("%.4f", v); }

}  // namespace

absl::Status SimCellOptions::Validate() const {
  if (!(pedestal_height_m >= 0.3 && pedestal_height_m <= 1.5)) {
    return Bad("SimCellOptions.pedestal_height_m", pedestal_height_m, "[0.3, 1.5]");
  }
  if (!(base_y_m >= -1.0 && base_y_m <= -0.45)) {
    return Bad("SimCellOptions.base_y_m", base_y_m, "[-1, -0.45]");
  }
  if (!(camera_height_m >= 1.0 && camera_height_m <= 3.0)) {
    return Bad("SimCellOptions.camera_height_m", camera_height_m, "[1, 3]");
  }
  if (!(pick_length_m > 0.1 && pick_length_m <= 1.3)) {
    return Bad("SimCellOptions.pick_length_m", pick_length_m, "(0.1, 1.3]");
  }
  if (!(pick_width_m > 0.1 && pick_width_m <= 0.9)) {
    return Bad("SimCellOptions.pick_width_m", pick_width_m, "(0.1, 0.9]");
  }
  if (!(heap_width_m > 0.1 && heap_width_m <= 0.9)) {
    return Bad("SimCellOptions.heap_width_m", heap_width_m, "(0.1, 0.9]");
  }
  return absl::OkStatus();
}

absl::Status SimLoadOptions::Validate() const {
  if (kind != "pallet" && kind != "heap" && kind != "bin") {
    return absl::InvalidArgumentError(
        absl::StrCat("SimLoadOptions.kind is '", kind, "', expected pallet, heap or bin"));
  }
  if (absl::Status s = box.Validate(); !s.ok()) return s;
  if (box.l > 0.6 || box.b > 0.6 || box.h > 0.5) {
    return absl::InvalidArgumentError("SimLoadOptions.box: sides up to 0.6 x 0.6 x 0.5 m");
  }
  if (layers < 1 || layers > 10) return Bad("SimLoadOptions.layers", layers, "[1, 10]");
  if (pattern != "grid" && pattern != "interlock") {
    return absl::InvalidArgumentError(
        absl::StrCat("SimLoadOptions.pattern is '", pattern, "', expected grid or interlock"));
  }
  if (!(gap_m >= 0 && gap_m <= 0.05)) return Bad("SimLoadOptions.gap_m", gap_m, "[0, 0.05]");
  if (heap_boxes < 1 || heap_boxes > 60) {
    return Bad("SimLoadOptions.heap_boxes", heap_boxes, "[1, 60]");
  }
  return absl::OkStatus();
}

absl::StatusOr<SimCell> MakeSimCell(const SimCellOptions& cell, const SimLoadOptions& load) {
  if (absl::Status s = cell.Validate(); !s.ok()) return s;
  if (absl::Status s = load.Validate(); !s.ok()) return s;
  SimCell out;
  CellLayout& layout = out.layout;
  layout.arm = cell.arm;
  // A cell stands its robot above the load it unloads: a pallet load
  // higher than the pedestal raises the base plate to 5 cm above its top.
  const double load_top = testing::kEurPalletHeight + load.layers * load.box.h;
  const double pedestal = load.kind == "pallet" ? std::max(cell.pedestal_height_m, load_top + 0.05)
                                                : cell.pedestal_height_m;
  layout.world_T_base = At({0, cell.base_y_m, pedestal});
  layout.world_T_camera = testing::LookAtCamera(Eigen::Vector3d::Zero(), cell.camera_height_m,
                                                /*tilt_deg=*/0, /*yaw_deg=*/0, /*roll_deg=*/0);
  layout.supports = testing::MakeEurPallet(Eigen::Isometry3d::Identity());
  const double place_y = 2 * cell.base_y_m;
  // The place pallet stands on a stand as much higher as the robot is (an
  // outfeed at the height the arm reaches, as the robot's own is).
  const double place_stand = pedestal - cell.pedestal_height_m;
  for (auto& part : testing::MakeEurPallet(At({0, place_y, place_stand}))) {
    part.name = "place_" + part.name;
    layout.supports.push_back(part);
  }
  if (place_stand > 0.0) {
    layout.supports.push_back(
        {"place_stand", {1.2, 0.8, place_stand}, At({0, place_y, 0.5 * place_stand})});
  }
  // The pedestal under the base plate (a UR5e's is 149 mm across).
  layout.supports.push_back(
      {"pedestal", {0.18, 0.18, pedestal}, At({0, cell.base_y_m, 0.5 * pedestal})});
  layout.pick_area = {Eigen::Vector3d(-0.7, -0.47, 0.0), Eigen::Vector3d(0.7, 0.47, 3.0)};
  layout.place_area = {Eigen::Vector3d(-0.7, place_y - 0.42, 0.0),
                       Eigen::Vector3d(0.7, place_y + 0.42, 3.0)};

  const BoxDims& d = load.box;
  int per_layer = 0;
  if (load.kind == "pallet") {
    out.boxes = PalletLoad(cell, load, &per_layer);
    out.description = absl::StrFormat(
        "pallet of %d layers (%s) of up to %d boxes %.3g x %.3g x %.3g m, %d boxes", load.layers,
        load.pattern, per_layer, d.l, d.b, d.h, static_cast<int>(out.boxes.size()));
  } else {
    const bool bin = load.kind == "bin";
    const double deck = testing::kEurPalletHeight + (bin ? 0.02 : 0.0);
    if (bin) {
      for (auto& part : Bin(cell, 0.25)) layout.supports.push_back(part);
    }
    absl::StatusOr<std::vector<testing::SceneBox>> heap =
        HeapLoad(cell, load, deck, bin ? 0.03 : 0.0);
    if (!heap.ok()) return heap.status();
    out.boxes = *std::move(heap);
    out.description = absl::StrFormat("%s of %d boxes %.3g x %.3g x %.3g m (seed %u)",
                                      bin ? "bin with a heap" : "heap on the pallet",
                                      static_cast<int>(out.boxes.size()), d.l, d.b, d.h, load.seed);
  }
  if (out.boxes.empty())
    return absl::InvalidArgumentError("no box of this size fits the pick area");

  // The place pattern: the largest grid with 1 cm between boxes on the
  // place pallet's area, flat (the face picked looks up again), far row first.
  const double px = d.l + 0.01, py = d.b + 0.01;
  out.place_columns = std::max(1, static_cast<int>((cell.pick_length_m + 0.01) / px + 1e-6));
  out.place_rows = std::max(1, static_cast<int>((cell.pick_width_m + 0.02) / py + 1e-6));
  const int per_place_layer = out.place_rows * out.place_columns;
  const int count = static_cast<int>(out.boxes.size());
  out.place_layers = (count + per_place_layer - 1) / per_place_layer;
  out.place_spacing_x_m = px;
  out.place_spacing_y_m = py;
  // Heaps hold boxes of any orientation: the daemon stacks them by the
  // height of the grasped axis, which it sets from the box size (h).
  out.place_layer_height_m = d.h;
  const Eigen::Vector3d origin_world(-0.5 * (out.place_columns - 1) * px,
                                     place_y - 0.5 * (out.place_rows - 1) * py,
                                     place_stand + testing::kEurPalletHeight);
  out.place_origin_base = layout.world_T_base.inverse() * origin_world;
  out.lift_height_m = (load.kind == "pallet" ? d.h : d.vec().maxCoeff()) + 0.05;
  out.face_check_history = load.kind == "pallet" ? 12 : 0;
  return out;
}

absl::StatusOr<std::string> RobotClientConfigText(const SimCell& cell, const std::string& box_spec,
                                                  const std::string& source) {
  const CellLayout& layout = cell.layout;
  const Eigen::Isometry3d base_T_camera = layout.world_T_base.inverse() * layout.world_T_camera;
  const Eigen::Quaterniond q(base_T_camera.linear());
  const Eigen::Vector3d c = base_T_camera.translation();
  const double floor_z = -layout.world_T_base.translation().z();
  // The clear pose: the emulator's home pose turned to face the pick
  // pallet (upper arm straight up, elbow up, the tool 0.39 m above the base
  // plate over the pallet's near edge, pointing down). The daemon's free
  // moves take the inverse kinematics solution nearest the current joints;
  // from here that is the elbow-up solution in front of the robot for every
  // box, where from a pose beside or behind the robot it is, for some boxes,
  // the solution reaching back over the shoulder, which sweeps the forearm
  // through the load. (The simulated camera does not render the arm; a real
  // one would see it here.)
  const ur::Joints clear_q{-M_PI / 2, -1.571, 1.571, -1.571, -1.571, 0.0};
  std::string joints;
  for (int i = 0; i < 6; ++i) absl::StrAppend(&joints, i ? ", " : "", Num(clear_q[i]));

  std::string text = absl::StrCat(
      "# cornerpose_robot_client configuration for the simulated cell (written by\n",
      "# cell_sim --write_robot_config; tests/support/cell_sim/sim_cell.h): ", cell.description,
      ".\n", "# A ", ur::ArmModelName(layout.arm),
      " on a pedestal between the pick pallet (base +y, under the camera) and the\n",
      "# place pallet (base -y). Metres, radians, seconds.\n\n",
      "perception {\n  server_address: \"localhost:50051\"\n  source: \"", source, "\"\n  ",
      box_spec, "\n  reconnect_initial_s: 0.5\n  reconnect_max_s: 5\n}\n\n",
      "robot {\n  host: \"127.0.0.1\"\n  dashboard_port: 29999\n  primary_port: 30001\n",
      "  rtde_port: 30004\n  arm_model: \"", ur::ArmModelName(layout.arm), "\"\n",
      "  rtde_frequency_hz: 125\n  connect_timeout_s: 5\n",
      "  # A simulated arm with no one near it: power on and release the brakes at\n",
      "  # start (a real cell leaves this off; see deploy/config/robot_client.textproto).\n",
      "  bring_up_at_start: true\n}\n\n", "# The camera straight above the pick pallet.\n",
      "base_pose_camera {\n  position { x: ", Num(c.x()), " y: ", Num(c.y()), " z: ", Num(c.z()),
      " }\n  orientation { w: ", Num(q.w()), " x: ", Num(q.x()), " y: ", Num(q.y()),
      " z: ", Num(q.z()), " }\n}\n\n",
      "# Both pallets and the space above them, never lower than 3 cm above the floor.\n",
      "workspace {\n  min { x: -0.75 y: -1.0 z: ", Num(floor_z + 0.03),
      " }\n  max { x: 0.75 y: 1.0 z: 0.8 }\n}\n\n",
      "selection {\n  max_grasp_tilt_deg: 30\n  min_score: 0.0\n  height_tie_m: 0.01\n",
      cell.face_check_history > 0
          ? absl::StrCat("  # A pallet holds one box lying one way: the last picks vote on\n",
                         "  # which face the pile shows.\n  face_check_history: ",
                         cell.face_check_history, "\n")
          : std::string(),
      "}\n\n", "gripper {\n  tcp_offset {\n    position { x: 0 y: 0 z: 0.10 }\n",
      "    rotation_vector { x: 0 y: 0 z: 0 }\n  }\n  suction_output: SUCTION_OUTPUT_KIND_TOOL\n",
      "  suction_output_index: 0\n  grasp_settle_s: 0.3\n  release_s: 0.3\n}\n\n",
      "# The held box rises at least this far above its grasp (its bottom 5 cm\n",
      "# above the boxes around it; the daemon lifts it higher when the pile\n",
      "# is, and checks the move to the place pallet against the pile) and comes\n",
      "# down onto its slot from as high, so it never sweeps through the layer\n", "# it joins.\n",
      "waypoints {\n  approach_distance_m: 0.10\n  retrieve_height_m: ", Num(cell.lift_height_m),
      "\n  place_approach_height_m: ", Num(cell.lift_height_m), "\n}\n\n",
      "# Every box has a slot on the place pallet: far row first, then towards\n# the robot.\n",
      "place_pattern {\n  origin {\n    position { x: ", Num(cell.place_origin_base.x()),
      " y: ", Num(cell.place_origin_base.y()), " z: ", Num(cell.place_origin_base.z()),
      " }\n    orientation { w: 1 x: 0 y: 0 z: 0 }\n  }\n  rows: ", cell.place_rows,
      "\n  columns: ", cell.place_columns, "\n  layers: ", cell.place_layers,
      "\n  spacing_x_m: ", Num(cell.place_spacing_x_m),
      "\n  spacing_y_m: ", Num(cell.place_spacing_y_m),
      "\n  layer_height_m: ", Num(cell.place_layer_height_m), "\n}\n\n",
      "# Free moves at two thirds of the UR5e's joint speed limit (pi rad/s).\n",
      "motion {\n  joint_speed_rad_s: 2.0\n  joint_acceleration_rad_s2: 3.0\n",
      "  linear_speed_m_s: 0.25\n  linear_acceleration_m_s2: 1.0\n}\n\n",
      "# The home pose facing the pick pallet: tool 0.39 m above the base plate at\n",
      "# (0.13, 0.49), pointing down, upper arm up, elbow up (see sim_cell.cc).\n",
      "clear_joints_rad: [", joints, "]\n\n",
      "status_listen_address: \"127.0.0.1:50061\"\ndry_run: false\nmax_picks: 0\n");
  return text;
}

}  // namespace cornerpose::cell_sim
