// cell_sim: the simulated robot cell as a process. The UR controller
// emulator (dashboard, primary, RTDE on their usual ports) acting on a
// simulated world (a pallet, heap or bin of boxes; suction, carrying,
// collisions), and a depth camera rendering that world into a frame
// directory that the virtual OpenNI2 camera serves to cornerpose_server
// (`cornerpose://virtual?follow=1`). Prints one line per pick and keeps a
// JSON report of every pick and the world's state.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/box/box_models.h"
#include "tests/support/cell_sim/sim_camera.h"
#include "tests/support/cell_sim/sim_cell.h"
#include "tests/support/ur_emulator/ur_emulator.h"

ABSL_FLAG(std::string, scene, "pallet", "The load: pallet, heap (on the pallet) or bin.");
ABSL_FLAG(std::string, box, "carton_s", "Box model (carton_s, carton_l, ...) or L,B,H in metres.");
ABSL_FLAG(int, layers, 3, "Pallet layers.");
ABSL_FLAG(std::string, pattern, "grid", "Pallet layer pattern: grid or interlock.");
ABSL_FLAG(int, heap_boxes, 8,
          "Boxes in a heap or bin (a heap of more than about 8 carton_s rarely fits the 1.25 x 0.8 "
          "m pick area).");
ABSL_FLAG(double, gap, 0.003, "Gap between pallet boxes, metres.");
ABSL_FLAG(uint32_t, seed, 1, "Layout and noise seed.");
ABSL_FLAG(std::string, sensor, "kinect", "Depth sensor model: kinect or ideal.");
ABSL_FLAG(std::string, frames_dir, "out/sim/frames", "Where the camera writes its frames.");
ABSL_FLAG(int, keep_frames, 4,
          "Frames kept in --frames_dir (the newest); more to look at a run afterwards.");
ABSL_FLAG(double, camera_max_fps, 10, "Most renders a second (wall); only when the world changed.");
ABSL_FLAG(double, camera_height, 2.0, "Camera height above the floor, metres.");
ABSL_FLAG(std::string, host, "127.0.0.1", "Address the emulator listens on.");
ABSL_FLAG(int, dashboard_port, 29999, "Dashboard server port.");
ABSL_FLAG(int, primary_port, 30001, "Primary interface port.");
ABSL_FLAG(int, rtde_port, 30004, "RTDE port.");
ABSL_FLAG(double, time_scale, 1.0, "Simulated seconds per wall-clock second (> 0).");
ABSL_FLAG(bool, collisions, true, "Check the arm and the held box for contact.");
ABSL_FLAG(std::string, report, "", "JSON report, rewritten after every pick.");
ABSL_FLAG(std::string, write_robot_config, "",
          "Write the daemon's configuration for this cell (textproto) to this file.");
ABSL_FLAG(std::string, source, "sim",
          "The perception source name the daemon's configuration uses.");
ABSL_FLAG(bool, config_only, false, "Write --write_robot_config and exit.");
ABSL_FLAG(int, protective_stop_after, 0,
          "Fault injection: once this many boxes are placed, a protective stop on the arm "
          "during the next program (0 = none). An operator clears it on the dashboard.");

namespace {

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

using namespace cornerpose;

nlohmann::json ReportJson(const std::string& description, const cell_sim::WorldSummary& s,
                          const std::vector<cell_sim::SimBox>& boxes) {
  nlohmann::json picks = nlohmann::json::array();
  for (const auto& p : s.picks) {
    picks.push_back({{"program", p.program},
                     {"result", cell_sim::PickResultName(p.result)},
                     {"box", p.box_id},
                     {"detail", p.detail},
                     {"arm_s", p.end_time_s - p.start_time_s},
                     {"wait_before_s", p.wait_before_s}});
  }
  nlohmann::json box_list = nlohmann::json::array();
  for (const auto& b : boxes) {
    const Eigen::Vector3d t = b.world_T_box.translation();
    box_list.push_back({{"id", b.id},
                        {"state", cell_sim::BoxStateName(b.state)},
                        {"centre", {t.x(), t.y(), t.z()}}});
  }
  return {{"scene", description},       {"boxes_total", s.boxes_total},
          {"in_pile", s.in_pile},       {"placed", s.placed},
          {"dropped", s.dropped},       {"held", s.held},
          {"collisions", s.collisions}, {"picks", picks},
          {"boxes", box_list}};
}

void WriteAtomically(const std::string& path, const std::string& text) {
  const std::string temp = path + ".tmp";
  {
    std::ofstream out(temp, std::ios::trunc);
    out << text;
  }
  std::error_code error;
  std::filesystem::rename(temp, path, error);
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "The simulated cell: a UR controller emulator acting on a world of boxes, and a depth "
      "camera rendering that world for the perception service.");
  absl::ParseCommandLine(argc, argv);

  cell_sim::SimLoadOptions load;
  load.kind = absl::GetFlag(FLAGS_scene);
  const std::string box_text = absl::GetFlag(FLAGS_box);
  absl::StatusOr<BoxDims> dims = BoxModelByName(box_text);
  std::string box_spec = absl::StrCat("box_model: \"", box_text, "\"");
  if (!dims.ok()) {
    dims = ParseBoxDims(box_text);
    if (!dims.ok()) {
      std::fprintf(stderr, "cell_sim: --box '%s': %s\n", box_text.c_str(),
                   std::string(dims.status().message()).c_str());
      return 2;
    }
    box_spec = absl::StrFormat("box { l: %.4f b: %.4f h: %.4f }", dims->l, dims->b, dims->h);
  }
  load.box = *dims;
  load.layers = absl::GetFlag(FLAGS_layers);
  load.pattern = absl::GetFlag(FLAGS_pattern);
  load.heap_boxes = absl::GetFlag(FLAGS_heap_boxes);
  load.gap_m = absl::GetFlag(FLAGS_gap);
  load.seed = absl::GetFlag(FLAGS_seed);
  cell_sim::SimCellOptions cell_options;
  cell_options.camera_height_m = absl::GetFlag(FLAGS_camera_height);
  absl::StatusOr<cell_sim::SimCell> cell = cell_sim::MakeSimCell(cell_options, load);
  if (!cell.ok()) {
    std::fprintf(stderr, "cell_sim: %s\n", std::string(cell.status().message()).c_str());
    return 2;
  }
  if (const std::string path = absl::GetFlag(FLAGS_write_robot_config); !path.empty()) {
    absl::StatusOr<std::string> text =
        cell_sim::RobotClientConfigText(*cell, box_spec, absl::GetFlag(FLAGS_source));
    if (!text.ok()) {
      std::fprintf(stderr, "cell_sim: %s\n", std::string(text.status().message()).c_str());
      return 1;
    }
    WriteAtomically(path, *text);
  }
  if (absl::GetFlag(FLAGS_config_only)) return 0;

  cell_sim::CellWorldOptions world_options;
  world_options.collision.enabled = absl::GetFlag(FLAGS_collisions);
  auto world = std::make_shared<cell_sim::CellWorld>(cell->layout, cell->boxes, world_options);

  cell_sim::SimCameraOptions camera_options;
  camera_options.directory = absl::GetFlag(FLAGS_frames_dir);
  camera_options.sensor = absl::GetFlag(FLAGS_sensor);
  camera_options.max_fps = absl::GetFlag(FLAGS_camera_max_fps);
  camera_options.keep_frames = absl::GetFlag(FLAGS_keep_frames);
  camera_options.noise_seed = load.seed * 7919u + 1;
  absl::StatusOr<std::unique_ptr<cell_sim::SimCamera>> camera =
      cell_sim::SimCamera::Start(world.get(), camera_options);
  if (!camera.ok()) {
    std::fprintf(stderr, "cell_sim: camera: %s\n", std::string(camera.status().message()).c_str());
    return 1;
  }

  ur_emulator::UrEmulatorOptions options;
  options.host = absl::GetFlag(FLAGS_host);
  options.dashboard_port = absl::GetFlag(FLAGS_dashboard_port);
  options.primary_port = absl::GetFlag(FLAGS_primary_port);
  options.rtde_port = absl::GetFlag(FLAGS_rtde_port);
  options.time_scale = absl::GetFlag(FLAGS_time_scale);
  options.model = cell->layout.arm;
  options.world = world;
  auto emulator = ur_emulator::UrEmulator::Start(options);
  if (!emulator.ok()) {
    std::fprintf(stderr, "cell_sim: %s\n", emulator.status().ToString().c_str());
    return 1;
  }

  const std::string report = absl::GetFlag(FLAGS_report);
  // Set by the pick listener (the controller's thread); the stop itself is
  // injected from the main thread, into the program that follows.
  const int stop_after = absl::GetFlag(FLAGS_protective_stop_after);
  std::atomic<bool> stop_armed{false};
  const std::string description = cell->description;
  world->SetPickListener([&](const cell_sim::PickEvent& p, const cell_sim::WorldSummary& s) {
    const int failed = static_cast<int>(std::count_if(s.picks.begin(), s.picks.end(), [](auto& e) {
      return e.result != cell_sim::PickResult::kPlaced;
    }));
    std::printf(
        "sim %s: %s%s%s (arm %.1f s, waited %.2f s) | placed %d of %d, %d left, %d failed, "
        "%d collisions\n",
        p.program.c_str(), cell_sim::PickResultName(p.result), p.detail.empty() ? "" : ": ",
        p.detail.c_str(), p.end_time_s - p.start_time_s, p.wait_before_s, s.placed, s.boxes_total,
        s.in_pile, failed, s.collisions);
    std::fflush(stdout);
    if (!report.empty())
      WriteAtomically(report, ReportJson(description, s, world->Boxes()).dump(1));
    if (stop_after > 0 && s.placed == stop_after && p.result == cell_sim::PickResult::kPlaced) {
      stop_armed = true;
    }
  });
  if (!report.empty()) {
    WriteAtomically(report, ReportJson(description, world->Summary(), world->Boxes()).dump(1));
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::printf(
      "cell_sim: %s; %s on %s, dashboard %d, primary %d, rtde %d, time scale %g; camera "
      "%.2f m above the pallet, %s model, frames in %s\n",
      description.c_str(), ur::ArmModelName(options.model), options.host.c_str(),
      (*emulator)->dashboard_port(), (*emulator)->primary_port(), (*emulator)->rtde_port(),
      options.time_scale, cell_options.camera_height_m, camera_options.sensor.c_str(),
      camera_options.directory.c_str());
  std::fflush(stdout);
  bool stop_injected = false;
  while (!g_stop) {
    // Armed, watch closely: at time scale 20 a 100 ms poll is two simulated
    // seconds, and the arm could reach the box and grip it in between.
    std::this_thread::sleep_for(std::chrono::milliseconds(stop_armed && !stop_injected ? 2 : 100));
    if (stop_armed && !stop_injected && (*emulator)->controller().Snapshot().program_running) {
      // Half a simulated second into the next program: the arm is on its way
      // to the approach point, nothing on the cup.
      std::this_thread::sleep_for(
          std::chrono::milliseconds(static_cast<int>(500.0 / options.time_scale)));
      (*emulator)->TriggerProtectiveStop();
      stop_injected = true;
      std::printf("sim: protective stop injected (after %d placed)\n", stop_after);
      std::fflush(stdout);
    }
  }
  std::printf("cell_sim: stopping\n");
  return 0;
}
