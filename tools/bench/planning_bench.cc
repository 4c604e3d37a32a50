// The daemon's work per pick, after the detection: choosing the box (with
// IK reachability for every candidate grasp), planning the waypoints (IK at
// each, the straight moves sampled every 2 mm), rendering the program.
// Cartons at the demo cell's camera, from the shipped configuration.
//
//   build/tools/planning_bench [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>
#include <vector>

#include "robot_client/config/robot_config.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/pick_plan.h"
#include "robot_client/planning/pick_selection.h"
#include "robot_client/planning/urscript_program.h"

namespace cornerpose::robot_client {
namespace {

const RobotClientOptions& Options() {
  static const RobotClientOptions options = [] {
    absl::StatusOr<RobotClientOptions> loaded = LoadRobotClientConfig(
        std::string(CORNERPOSE_SOURCE_DIR) + "/deploy/config/robot_client.textproto");
    if (!loaded.ok()) {
      std::fprintf(stderr, "%s\n", loaded.status().ToString().c_str());
      std::abort();
    }
    return *loaded;
  }();
  return options;
}

// `n` cartons lying flat on the table around the point under the camera.
std::vector<DetectedBox> Cartons(int n) {
  const RobotClientOptions& options = Options();
  const Eigen::Vector3d centre = options.base_T_camera.translation();
  std::vector<DetectedBox> boxes;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d base_T_box = Eigen::Isometry3d::Identity();
    base_T_box.linear() = Eigen::AngleAxisd(0.4 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    base_T_box.translation() =
        Eigen::Vector3d(centre.x() - 0.3 + 0.15 * (i % 5), centre.y() - 0.15 + 0.3 * (i / 5),
                        0.5 * options.perception.box.h);
    DetectedBox box;
    box.camera_T_box = options.base_T_camera.inverse() * base_T_box;
    box.grasp_face = BoxFace::kPlusZ;
    box.score = 0.5 + 0.05 * i;
    boxes.push_back(box);
  }
  return boxes;
}

void BM_SelectPick(benchmark::State& state) {
  const RobotClientOptions& o = Options();
  const std::vector<DetectedBox> boxes = Cartons(static_cast<int>(state.range(0)));
  const Reachability reachable = MakeIkReachability(o.robot.arm_model, o.gripper.flange_T_tcp);
  for (auto _ : state) {
    PickSelection s = SelectPick(boxes, o.base_T_camera, o.perception.box, o.selection, o.workspace,
                                 o.waypoints, reachable);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_SelectPick)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);

void BM_PlanAndRender(benchmark::State& state) {
  const RobotClientOptions& o = Options();
  const std::vector<DetectedBox> boxes = Cartons(1);
  const BoxInBase box = BoxToBase(boxes[0], o.base_T_camera, o.perception.box);
  for (auto _ : state) {
    absl::StatusOr<PickPlan> plan = PlanPickForSlot(o, *o.clear_joints, box, 0);
    if (!plan.ok()) {
      state.SkipWithError(std::string(plan.status().message()).c_str());
      break;
    }
    absl::StatusOr<std::string> program =
        RenderPickProgram("pick_0001", *plan, o.gripper, o.motion, *o.clear_joints);
    benchmark::DoNotOptimize(program);
  }
}
BENCHMARK(BM_PlanAndRender)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace cornerpose::robot_client

BENCHMARK_MAIN();
