// make_frames: renders seeded synthetic box scenes (the tests' scene
// generator: ray casting with a Kinect v1 noise model) into a directory of
// recorded frames with exact ground truth.
//
//   make_frames --out DIR [--kind isolated|heap|pallet|cell|mixed] [--count N]
//               [--seed S] [--box NAME|L,B,H] [--pcd]
//
// Writes per frame NAME.png (16-bit depth, millimetres, 0 = no return) and,
// with --pcd, NAME.pcd (organized binary cloud); NAME.json with the ground
// truth in the format of ../shared/tools/score.py; and for the set
// intrinsics.txt ("width,height,fx,fy,cx,cy") and index.json. The same
// arguments always give the same frames.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "common/io/cloud_io.h"
#include "common/box/box_models.h"
#include "tests/support/scene_generator.h"

namespace cornerpose {
namespace {

nlohmann::json Matrix(const Eigen::Isometry3d& T) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 4; ++c) row.push_back(T.matrix()(r, c));
    rows.push_back(row);
  }
  return rows;
}

struct Args {
  std::string out, kind = "mixed", box = "carton_s";
  int count = 6;
  uint32_t seed = 1;
  bool pcd = false;
};

int Run(const Args& a) {
  absl::StatusOr<BoxDims> dims = ParseBoxDims(a.box);
  if (!dims.ok()) {
    std::fprintf(stderr, "make_frames: %s\n", dims.status().ToString().c_str());
    return 2;
  }
  std::filesystem::create_directories(a.out);
  nlohmann::json index = {{"set", std::filesystem::path(a.out).filename().string()},
                          {"scenes", nlohmann::json::array()}};
  CameraIntrinsics camera;
  for (int i = 0; i < a.count; ++i) {
    static const char* kKinds[] = {"isolated", "heap", "pallet"};
    const std::string kind = a.kind == "mixed" ? kKinds[i % 3] : a.kind;
    const uint32_t seed = a.seed * 1000 + i;
    testing::Scene scene;
    if (kind == "isolated") {
      scene = testing::MakeIsolatedScene(*dims, 1 + i % 4, seed);
    } else if (kind == "heap") {
      scene = testing::MakeHeapScene(*dims, 6 + i % 8, seed);
    } else if (kind == "cell") {
      scene = testing::MakeCellScene(*dims, 5 + i % 4, seed);
    } else if (kind == "pallet") {
      scene = testing::MakePalletScene(*dims, 3 + i % 2, 2 + i % 3, 1 + i % 2,
                                       0.002 + 0.001 * (i % 3), i % 4, seed);
    } else {
      std::fprintf(stderr, "make_frames: unknown --kind %s\n", kind.c_str());
      return 2;
    }
    const testing::RenderedScene r = testing::Render(scene);
    camera = r.camera;
    const std::string id = absl::StrFormat("%s_%03d", kind, i);
    std::vector<uint16_t> depth(r.cloud.size(), 0);
    for (size_t p = 0; p < r.cloud.size(); ++p) {
      const float z = r.cloud.xyz[p].z();
      if (std::isfinite(z)) depth[p] = static_cast<uint16_t>(std::lround(z * 1000.0));
    }
    absl::Status s =
        WriteDepthPng(a.out + "/" + id + ".png", depth, r.camera.width, r.camera.height);
    if (s.ok() && a.pcd) s = SavePcd(a.out + "/" + id + ".pcd", r.cloud);
    if (!s.ok()) {
      std::fprintf(stderr, "make_frames: %s\n", s.ToString().c_str());
      return 1;
    }
    nlohmann::json gt = {{"scene_id", id},
                         {"set", index["set"]},
                         {"type", kind},
                         {"hard", false},
                         {"target_dims_name", a.box},
                         {"target_dims", {dims->l, dims->b, dims->h}},
                         {"camera",
                          {{"width", camera.width},
                           {"height", camera.height},
                           {"fx", camera.fx},
                           {"fy", camera.fy},
                           {"cx", camera.cx},
                           {"cy", camera.cy}}},
                         {"generator", {{"tool", "cornerpose make_frames"}, {"seed", seed}}},
                         {"boxes", nlohmann::json::array()}};
    for (size_t b = 0; b < r.boxes.size(); ++b) {
      const testing::GroundTruthBox& g = r.boxes[b];
      gt["boxes"].push_back({{"id", b + 1},
                             {"target", g.target},
                             {"dims", {g.dims.l, g.dims.b, g.dims.h}},
                             {"dims_name", a.box},
                             {"T_cam_box", Matrix(g.camera_T_box)},
                             {"visib_fract", g.visib_fract},
                             {"grasp_face", BoxFaceName(g.grasp_face)},
                             {"pickable", g.pickable}});
    }
    std::ofstream(a.out + "/" + id + ".json") << gt.dump(1) << "\n";
    index["scenes"].push_back({{"scene_id", id},
                               {"type", kind},
                               {"files", {{"gt", id + ".json"}, {"depth_png", id + ".png"}}}});
    std::printf("%s: %zu boxes\n", id.c_str(), r.boxes.size());
  }
  std::ofstream(a.out + "/index.json") << index.dump(1) << "\n";
  std::ofstream(a.out + "/intrinsics.txt")
      << camera.width << "," << camera.height << "," << camera.fx << "," << camera.fy << ","
      << camera.cx << "," << camera.cy << "\n";
  return 0;
}

}  // namespace
}  // namespace cornerpose

int main(int argc, char** argv) {
  cornerpose::Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    const bool has_value = i + 1 < argc;
    if (k == "--pcd") {
      a.pcd = true;
    } else if (k == "--out" && has_value) {
      a.out = argv[++i];
    } else if (k == "--kind" && has_value) {
      a.kind = argv[++i];
    } else if (k == "--box" && has_value) {
      a.box = argv[++i];
    } else if (k == "--count" && has_value && absl::SimpleAtoi(argv[i + 1], &a.count)) {
      ++i;
    } else if (k == "--seed" && has_value && absl::SimpleAtoi(argv[i + 1], &a.seed)) {
      ++i;
    } else {
      std::fprintf(
          stderr,
          "usage: make_frames --out DIR [--kind isolated|heap|pallet|cell|mixed] [--count N] "
          "[--seed S] [--box NAME|L,B,H] [--pcd]\n");
      return 2;
    }
  }
  if (a.out.empty() || a.count < 1) {
    std::fprintf(stderr, "make_frames: --out is required and --count must be positive\n");
    return 2;
  }
  return cornerpose::Run(a);
}
