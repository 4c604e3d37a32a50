// Speed of the detector, stage by stage, on a 640x480 clutter frame, and
// what the fast path costs in accuracy against the full-resolution
// reference (every pixel scored, every neighbour in the disc), in one run.
//
//   build/tools/detector_bench [--benchmark_repetitions=9]
//
// BM_Detect: one seeded heap of 12 cartons from the scene generator (exact
// ground truth). Set CORNERPOSE_BENCH_CLOUD=FILE and CORNERPOSE_BENCH_BOX=L,B,H
// (or a model name) to time a recorded frame instead.
// BM_ClutterSet: the 30 Hz target's frames, 640x480 clutter of the dev kinds
// (heaps and pallets, Kinect and active stereo with colour, two box sizes,
// several seeds), each detected once per iteration; its counters are the
// median and p90 of the detector's own reported time per frame and the
// correct / pickable boxes over the set, and (min_*_ms) each frame's fastest
// stage times summed over the set; CORNERPOSE_BENCH_MIN_TIME=S runs it for
// S seconds instead of 3.
// BM_CompareFrames: a stream's test for an unchanged frame (frame_change.h).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "common/box/box_models.h"
#include "common/io/cloud_io.h"
#include "common/perception/detector.h"
#include "common/perception/frame_change.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"
#include "tests/support/scene_kinds.h"
#include "tests/support/sensor_options.h"

namespace cornerpose {
namespace {

struct Frame {
  PointCloud cloud;
  BoxDims dims;
  std::vector<testing::GroundTruthBox> truth;  // empty for a recorded frame
};

const Frame& TheFrame() {
  static const Frame kFrame = [] {
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
  return kFrame;
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
int CorrectBoxes(const Detection& d, const std::vector<testing::GroundTruthBox>& truth) {
  int n = 0;
  for (const testing::GroundTruthBox& gt : truth) {
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
    state.counters["correct"] = CorrectBoxes(last, TheFrame().truth);
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

// The clutter set: heaps and pallets of touching cartons (with boxes of
// another size on them), Kinect and stereo, carton_s and carton_l, 3 seeds.
const std::vector<Frame>& ClutterSet() {
  static const std::vector<Frame> kFrames = [] {
    std::vector<Frame> out;
    struct Spec {
      testing::SensorKind sensor;
      const char* kind;
      BoxDims dims;
    };
    const BoxDims carton_s{0.30, 0.20, 0.15}, carton_l{0.40, 0.30, 0.25};
    const Spec specs[] = {
        {testing::SensorKind::kKinect, "heap", carton_s},
        {testing::SensorKind::kKinect, "pallet", carton_s},
        {testing::SensorKind::kKinect, "touching", carton_l},
        {testing::SensorKind::kStereo, "heap", carton_l},
        {testing::SensorKind::kStereo, "touching", carton_s},
    };
    for (int seed = 0; seed < 3; ++seed) {
      for (const Spec& spec : specs) {
        testing::SensorOptions sensor;
        sensor.kind = spec.sensor;
        sensor.color.enabled = spec.sensor != testing::SensorKind::kKinect;
        const CameraIntrinsics k = *testing::SensorIntrinsics(spec.sensor, 640, 480);
        const testing::CameraPlacement place = testing::SensorPlacement(spec.sensor, k);
        std::string type;
        const int i = 2 * seed + 1;
        absl::StatusOr<testing::Scene> scene =
            testing::MakeSceneOfKind(spec.kind, spec.dims, i, 7100 + 10 * seed, place, &type);
        if (!scene.ok()) {
          std::fprintf(stderr, "detector_bench: %s\n", scene.status().ToString().c_str());
          std::exit(1);
        }
        const testing::RenderedScene r = testing::Render(*scene, sensor);
        out.push_back({r.cloud, spec.dims, r.boxes});
      }
    }
    return out;
  }();
  return kFrames;
}

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0
                   : v[static_cast<size_t>(std::lround(q * static_cast<double>(v.size() - 1)))];
}

void BM_ClutterSet(benchmark::State& state) {
  const std::vector<Frame>& frames = ClutterSet();
  std::vector<double> total, edges, segments, faces, poses;
  // Per frame, each stage's fastest time over the iterations: summed over
  // the set, a measure of the work that this noisy machine's steal times
  // blur least (compare builds with --benchmark_min_time=10).
  std::vector<StageTimings> fastest(frames.size());
  for (StageTimings& t : fastest) {
    t.total_ms = t.edge_points_ms = t.edge_segments_ms = t.faces_ms = t.poses_ms = 1e9;
  }
  int correct = 0, pickable = 0, returned = 0, proposed = 0, refined = 0, accepted = 0;
  // A digest of what was found (poses, scores, edge points, segments): equal
  // digests across builds mean the same detections.
  double digest = 0.0;
  for (auto _ : state) {
    correct = pickable = returned = proposed = refined = accepted = 0;
    digest = 0.0;
    for (size_t i = 0; i < frames.size(); ++i) {
      const Frame& f = frames[i];
      DetectorOptions o;
      o.box = f.dims;
      o.num_threads = static_cast<int>(state.range(0));
      absl::StatusOr<Detection> d = DetectBoxes(f.cloud, o);
      if (!d.ok()) {
        state.SkipWithError(d.status().ToString().c_str());
        return;
      }
      total.push_back(d->timings.total_ms);
      edges.push_back(d->timings.edge_points_ms);
      segments.push_back(d->timings.edge_segments_ms);
      faces.push_back(d->timings.faces_ms);
      poses.push_back(d->timings.poses_ms);
      StageTimings& best = fastest[i];
      best.total_ms = std::min(best.total_ms, d->timings.total_ms);
      best.edge_points_ms = std::min(best.edge_points_ms, d->timings.edge_points_ms);
      best.edge_segments_ms = std::min(best.edge_segments_ms, d->timings.edge_segments_ms);
      best.faces_ms = std::min(best.faces_ms, d->timings.faces_ms);
      best.poses_ms = std::min(best.poses_ms, d->timings.poses_ms);
      correct += CorrectBoxes(*d, f.truth);
      proposed += d->hypotheses.proposed;
      refined += d->hypotheses.refined;
      accepted += d->hypotheses.accepted;
      returned += static_cast<int>(d->boxes.size());
      for (const DetectedBox& b : d->boxes) {
        const Eigen::Vector3d t = b.camera_T_box.translation();
        digest += 1000.0 * (t.x() + 2.0 * t.y() + 3.0 * t.z()) + b.score;
      }
      digest += 1e-3 * static_cast<double>(d->edge_points.size() + 7 * d->segments.size());
      for (const auto& gt : f.truth) pickable += gt.pickable;
    }
  }
  state.counters["frames"] = static_cast<double>(frames.size());
  state.counters["median_ms"] = Quantile(total, 0.5);
  state.counters["p90_ms"] = Quantile(total, 0.9);
  state.counters["edges_ms"] = Quantile(edges, 0.5);
  state.counters["segments_ms"] = Quantile(segments, 0.5);
  state.counters["faces_ms"] = Quantile(faces, 0.5);  // beside the segments, own thread
  state.counters["poses_ms"] = Quantile(poses, 0.5);
  StageTimings sum_fastest;
  for (const StageTimings& t : fastest) {
    sum_fastest.total_ms += t.total_ms;
    sum_fastest.edge_points_ms += t.edge_points_ms;
    sum_fastest.edge_segments_ms += t.edge_segments_ms;
    sum_fastest.faces_ms += t.faces_ms;
    sum_fastest.poses_ms += t.poses_ms;
  }
  state.counters["min_total_ms"] = sum_fastest.total_ms;
  state.counters["min_edges_ms"] = sum_fastest.edge_points_ms;
  state.counters["min_segments_ms"] = sum_fastest.edge_segments_ms;
  state.counters["min_faces_ms"] = sum_fastest.faces_ms;
  state.counters["min_poses_ms"] = sum_fastest.poses_ms;
  state.counters["correct"] = correct;
  state.counters["returned"] = returned;
  state.counters["pickable"] = pickable;
  state.counters["digest"] = digest;
  state.counters["proposed"] = proposed;
  state.counters["refined"] = refined;
  state.counters["accepted"] = accepted;
}
// Seconds each BM_ClutterSet run lasts at least: CORNERPOSE_BENCH_MIN_TIME,
// else 3 (a flag cannot override a benchmark's own MinTime).
double ClutterMinTime() {
  const char* s = std::getenv("CORNERPOSE_BENCH_MIN_TIME");
  const double t = s != nullptr ? std::atof(s) : 0.0;
  return t > 0.0 ? t : 3.0;
}
// Arg: threads.
BENCHMARK(BM_ClutterSet)
    ->ArgNames({"threads"})
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(ClutterMinTime());

// What a stream pays to tell whether a frame shows the same scene as the one
// it last detected on (CompareFrames, the windows sized for the box): the
// benchmark frame against itself rendered with new noise.
void BM_CompareFrames(benchmark::State& state) {
  const BoxDims dims{0.30, 0.20, 0.15};
  testing::Scene scene = testing::MakeHeapScene(dims, 12, 7);
  const PointCloud before = testing::Render(scene).cloud;
  scene.look_seed = scene.LookSeed();
  scene.noise_seed += 1000;
  const PointCloud after = testing::Render(scene).cloud;
  FrameChangeOptions o;
  o.box_side_m = dims.h;
  o.focal_px = scene.camera.fx;
  int same = 0;
  for (auto _ : state) {
    absl::StatusOr<FrameChange> change = CompareFrames(before, after, o);
    same += change.ok() && change->same_scene;
    benchmark::DoNotOptimize(change);
  }
  state.counters["same_scene"] =
      static_cast<double>(same) / std::max<int64_t>(1, state.iterations());
}
BENCHMARK(BM_CompareFrames)->Unit(benchmark::kMillisecond);

// How soon a cancelled detection returns: each clutter frame is detected
// and cancelled from another thread after a delay spread over the frame's
// detection time (1/16 ... 15/16 of it); the counters are the latencies
// from Cancel() to DetectBoxes returning (the issue 11 aim: ~50 ms).
void BM_CancelLatency(benchmark::State& state) {
  const std::vector<Frame>& frames = ClutterSet();
  std::vector<double> latency;
  int stopped = 0, finished = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < frames.size(); ++i) {
      const Frame& f = frames[i];
      DetectorOptions o;
      o.box = f.dims;
      o.num_threads = 2;
      const absl::StatusOr<Detection> full = DetectBoxes(f.cloud, o);
      const double full_ms = full.ok() ? full->timings.total_ms : 0.0;
      for (int k = 1; k < 16; k += 2) {
        const CancelToken token;
        std::chrono::steady_clock::time_point cancelled_at;
        std::thread canceller([&] {
          std::this_thread::sleep_for(
              std::chrono::microseconds(static_cast<int64_t>(1000.0 * full_ms * k / 16.0)));
          cancelled_at = std::chrono::steady_clock::now();
          token.Cancel();
        });
        const absl::StatusOr<Detection> d = DetectBoxes(f.cloud, o, token);
        const auto returned_at = std::chrono::steady_clock::now();
        canceller.join();
        if (d.ok()) {
          ++finished;  // ended before the cancel
          continue;
        }
        ++stopped;
        latency.push_back(std::max(
            0.0, std::chrono::duration<double, std::milli>(returned_at - cancelled_at).count()));
      }
    }
  }
  state.counters["stopped"] = stopped;
  state.counters["finished"] = finished;
  state.counters["median_ms"] = Quantile(latency, 0.5);
  state.counters["p99_ms"] = Quantile(latency, 0.99);
  state.counters["max_ms"] =
      latency.empty() ? 0.0 : *std::max_element(latency.begin(), latency.end());
}
BENCHMARK(BM_CancelLatency)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace cornerpose

BENCHMARK_MAIN();
