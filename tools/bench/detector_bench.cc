// Speed of the detector, stage by stage, on a 640x480 clutter frame, and
// what the fast path costs in accuracy against the full-resolution
// reference (every pixel scored, every neighbour in the disc), in one run.
//
//   build/tools/detector_bench [--benchmark_repetitions=9]
//
// The frame is a seeded heap of 12 cartons from the scene generator (exact
// ground truth). Set CORNERPOSE_BENCH_CLOUD=FILE and CORNERPOSE_BENCH_BOX=L,B,H
// (or a model name) to time a recorded frame instead.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "common/io/cloud_io.h"
#include "common/box/box_models.h"
#include "common/perception/detector.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"

namespace cornerpose {
namespace {

struct Frame {
  PointCloud cloud;
  BoxDims dims;
  std::vector<testing::GroundTruthBox> truth;  // empty for a recorded frame
};

const Frame& TheFrame() {
  static const Frame frame = [] {
    Frame f;
    const char* path = std::getenv("CORNERPOSE_BENCH_CLOUD");
    if (path != nullptr) {
      const char* box = std::getenv("CORNERPOSE_BENCH_BOX");
      absl::StatusOr<PointCloud> cloud = LoadPointCloud(path);
      absl::StatusOr<BoxDims> dims = ParseBoxDims(box != nullptr ? box : "carton_s");
      if (!cloud.ok() || !dims.ok()) {
        std::fprintf(stderr, "detector_bench: %s %s\n", cloud.status().ToString().c_str(),
                     dims.status().ToString().c_str());
        std::exit(1);
      }
      f.cloud = *cloud;
      f.dims = *dims;
      return f;
    }
    f.dims = {0.30, 0.20, 0.15};
    const testing::RenderedScene scene = testing::Render(testing::MakeHeapScene(f.dims, 12, 7));
    f.cloud = scene.cloud;
    f.truth = scene.boxes;
    return f;
  }();
  return frame;
}

DetectorOptions Options(bool reference, int threads) {
  DetectorOptions o;
  o.box = TheFrame().dims;
  o.num_threads = threads;
  if (reference) {
    o.edge_points.coarse_step = 1;  // score every pixel
    o.edge_points.max_samples = 0;  // every neighbour in the disc
  }
  return o;
}

// Pickable ground-truth boxes found within 10 mm and 5 degrees.
int CorrectBoxes(const Detection& d) {
  int n = 0;
  for (const testing::GroundTruthBox& gt : TheFrame().truth) {
    if (!gt.pickable) continue;
    for (const DetectedBox& b : d.boxes) {
      const PoseError e = ComparePoses(b.camera_T_box, gt.camera_T_box, gt.dims);
      if (e.translation_m <= 0.010 && e.rotation_deg <= 5.0) {
        ++n;
        break;
      }
    }
  }
  return n;
}

void BM_Detect(benchmark::State& state) {
  const bool reference = state.range(0) != 0;
  const DetectorOptions options = Options(reference, static_cast<int>(state.range(1)));
  StageTimings sum;
  Detection last;
  for (auto _ : state) {
    absl::StatusOr<Detection> d = DetectBoxes(TheFrame().cloud, options);
    if (!d.ok()) {
      state.SkipWithError(d.status().ToString().c_str());
      return;
    }
    sum.preprocess_ms += d->timings.preprocess_ms;
    sum.edge_points_ms += d->timings.edge_points_ms;
    sum.edge_segments_ms += d->timings.edge_segments_ms;
    sum.clubbing_ms += d->timings.clubbing_ms;
    sum.poses_ms += d->timings.poses_ms;
    last = *std::move(d);
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["pre_ms"] = sum.preprocess_ms / n;
  state.counters["edges_ms"] = sum.edge_points_ms / n;
  state.counters["segments_ms"] = sum.edge_segments_ms / n;
  state.counters["club_ms"] = sum.clubbing_ms / n;
  state.counters["poses_ms"] = sum.poses_ms / n;
  state.counters["edge_pts"] = static_cast<double>(last.edge_points.size());
  state.counters["boxes"] = static_cast<double>(last.boxes.size());
  state.counters["hyp"] = last.hypotheses.proposed;
  state.counters["refined"] = last.hypotheses.refined;
  if (!TheFrame().truth.empty()) {
    int pickable = 0;
    for (const auto& gt : TheFrame().truth) pickable += gt.pickable;
    state.counters["pickable"] = pickable;
    state.counters["correct"] = CorrectBoxes(last);
  }
}
// Args: {reference (0 fast, 1 full resolution), threads}
BENCHMARK(BM_Detect)
    ->ArgNames({"reference", "threads"})
    ->Args({0, 1})
    ->Args({0, 2})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
}  // namespace cornerpose

BENCHMARK_MAIN();
