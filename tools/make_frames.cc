// make_frames: renders seeded synthetic box scenes (the tests' scene
// generator: ray casting with a structured-light, time-of-flight or active
// stereo noise model, and optionally a registered colour image) into a
// directory of recorded frames with exact ground truth.
//
//   make_frames --out DIR [--kind KIND] [--count N] [--seed S] [--box NAME|L,B,H]
//               [--sensor kinect|tof|stereo] [--resolution WxH] [--color] [--pcd]
//               [--take_every N]
//
// Kinds: isolated, heap, pallet (a grid with 2-4 mm gaps, 1-2 layers),
// touching (a pallet of touching cartons, 0-3 mm gaps, at one layer or two
// heights, with 1-3 boxes of another size on the top layer), cell (the demo
// cell's view), mixed (isolated, heap, pallet in turn) and depal (isolated,
// heap, touching at one layer, touching at two heights in turn).
//
// --take_every N makes a recording of one scene instead (frames rec_0000,
// rec_0001, ...; the first scene of --kind): frame i shows it with i / N of
// its boxes taken away, the highest first, as a cell empties a pallet, and
// every frame draws new sensor noise on the same surfaces (a camera watching
// the cell at N frames a pick).
//
// Writes per frame NAME.png (16-bit depth, millimetres, 0 = no return), with
// --color NAME.color.png (8-bit RGB registered to the depth; grey infrared
// intensity for tof), with --pcd NAME.pcd (organized binary cloud, with an
// rgb field under --color); NAME.json with the ground truth in the format of
// ../shared/tools/score.py; and for the set intrinsics.txt
// ("width,height,fx,fy,cx,cy") and index.json. The same arguments always give
// the same frames; the kinect frames are those of earlier versions.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "common/box/box_models.h"
#include "common/io/cloud_io.h"
#include "common/io/png_io.h"
#include "tests/support/scene_generator.h"
#include "tests/support/scene_kinds.h"

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
  std::string out, kind = "mixed", box = "carton_s", sensor = "kinect";
  int count = 6, width = 0, height = 0, take_every = 0;
  uint32_t seed = 1;
  bool pcd = false, color = false;
};

// An organized binary PCD with x y z and a packed rgb (uint32 0x00RRGGBB,
// as PCL writes PointXYZRGB).
absl::Status SaveColorPcd(const std::string& path, const PointCloud& cloud) {
  struct Closer {
    void operator()(FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<FILE, Closer> fp(std::fopen(path.c_str(), "wb"));
  if (fp == nullptr) return absl::InternalError(path + ": cannot open for writing");
  const std::string header = absl::StrFormat(
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\n"
      "SIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH %d\nHEIGHT %d\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS %d\nDATA binary\n",
      cloud.width, cloud.height, cloud.size());
  std::vector<uint32_t> data(4 * cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    std::memcpy(&data[4 * i], cloud.xyz[i].data(), 3 * sizeof(float));
    data[4 * i + 3] = cloud.rgb[i];
  }
  bool ok = std::fwrite(header.data(), 1, header.size(), fp.get()) == header.size();
  ok = ok && std::fwrite(data.data(), sizeof(uint32_t), data.size(), fp.get()) == data.size();
  ok = (std::fclose(fp.release()) == 0) && ok;
  return ok ? absl::OkStatus() : absl::DataLossError(path + ": write failed");
}

absl::Status SaveColorPng(const std::string& path, const PointCloud& cloud) {
  std::vector<uint8_t> bytes(3 * cloud.rgb.size());
  for (size_t i = 0; i < cloud.rgb.size(); ++i) {
    bytes[3 * i] = (cloud.rgb[i] >> 16) & 0xFF;
    bytes[3 * i + 1] = (cloud.rgb[i] >> 8) & 0xFF;
    bytes[3 * i + 2] = cloud.rgb[i] & 0xFF;
  }
  return WriteRgbPng(path, bytes, cloud.width, cloud.height);
}

// The box whose top reaches highest above the floor (a cell takes it next).
size_t HighestBox(const testing::Scene& scene) {
  size_t best = 0;
  double best_top = -1e9;
  for (size_t i = 0; i < scene.boxes.size(); ++i) {
    const testing::SceneBox& box = scene.boxes[i];
    double top = -1e9;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1 ? 0.5 : -0.5) * box.dims.l,
                                   (c & 2 ? 0.5 : -0.5) * box.dims.b,
                                   (c & 4 ? 0.5 : -0.5) * box.dims.h);
      top = std::max(top, (box.world_T_box * corner).z());
    }
    if (top > best_top) {
      best_top = top;
      best = i;
    }
  }
  return best;
}

int Run(const Args& a) {
  absl::StatusOr<BoxDims> dims = ParseBoxDims(a.box);
  absl::StatusOr<testing::SensorKind> sensor_kind = testing::ParseSensorKind(a.sensor);
  absl::StatusOr<CameraIntrinsics> intrinsics =
      sensor_kind.ok() ? testing::SensorIntrinsics(*sensor_kind, a.width, a.height)
                       : absl::StatusOr<CameraIntrinsics>(sensor_kind.status());
  for (const absl::Status& s : {dims.status(), intrinsics.status()}) {
    if (!s.ok()) {
      std::fprintf(stderr, "make_frames: %s\n", s.ToString().c_str());
      return 2;
    }
  }
  testing::SensorOptions sensor;
  sensor.kind = *sensor_kind;
  sensor.color.enabled = a.color;
  const testing::CameraPlacement placement = testing::SensorPlacement(sensor.kind, *intrinsics);

  std::filesystem::create_directories(a.out);
  nlohmann::json index = {{"set", std::filesystem::path(a.out).filename().string()},
                          {"sensor", a.sensor},
                          {"scenes", nlohmann::json::array()}};
  CameraIntrinsics camera = *intrinsics;
  std::optional<testing::Scene> recorded;  // --take_every: the scene recorded, and its type
  std::string recorded_type;
  for (int i = 0; i < a.count; ++i) {
    static const char* kMixed[] = {"isolated", "heap", "pallet"};
    static const char* kDepal[] = {"isolated", "heap", "touching1", "touching2"};
    const std::string kind = a.kind == "mixed"   ? kMixed[i % 3]
                             : a.kind == "depal" ? kDepal[i % 4]
                                                 : a.kind;
    const uint32_t seed = a.seed * 1000 + i;
    std::string type;
    absl::StatusOr<testing::Scene> scene =
        a.take_every > 0 && recorded
            ? absl::StatusOr<testing::Scene>(*recorded)
            : testing::MakeSceneOfKind(kind, *dims, a.take_every > 0 ? 0 : i,
                                       a.take_every > 0 ? a.seed * 1000 : seed, placement, &type);
    if (!scene.ok()) {
      std::fprintf(stderr, "make_frames: %s\n", scene.status().ToString().c_str());
      return 2;
    }
    if (a.take_every > 0) {
      if (!recorded) {
        recorded = *scene;
        recorded->look_seed = recorded->LookSeed();
        recorded_type = type;
      }
      type = recorded_type;
      scene->noise_seed = recorded->noise_seed + static_cast<uint32_t>(i);
      for (int taken = 0; taken < i / a.take_every && !scene->boxes.empty(); ++taken) {
        scene->boxes.erase(scene->boxes.begin() + HighestBox(*scene));
      }
    }
    const testing::RenderedScene r = testing::Render(*scene, sensor);
    camera = r.camera;
    const std::string id =
        a.take_every > 0 ? absl::StrFormat("rec_%04d", i) : absl::StrFormat("%s_%03d", kind, i);
    std::vector<uint16_t> depth(r.cloud.size(), 0);
    for (size_t p = 0; p < r.cloud.size(); ++p) {
      const float z = r.cloud.xyz[p].z();
      if (std::isfinite(z)) depth[p] = static_cast<uint16_t>(std::lround(z * 1000.0));
    }
    const std::string base = a.out + "/" + id;
    absl::Status s = WriteDepthPng(base + ".png", depth, r.camera.width, r.camera.height);
    if (s.ok() && a.color) s = SaveColorPng(base + ".color.png", r.cloud);
    if (s.ok() && a.pcd)
      s = a.color ? SaveColorPcd(base + ".pcd", r.cloud) : SavePcd(base + ".pcd", r.cloud);
    if (!s.ok()) {
      std::fprintf(stderr, "make_frames: %s\n", s.ToString().c_str());
      return 1;
    }
    nlohmann::json gt = {{"scene_id", id},
                         {"set", index["set"]},
                         {"type", type},
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
                         {"generator",
                          {{"tool", "cornerpose make_frames"},
                           {"seed", seed},
                           {"sensor", a.sensor},
                           {"kind", kind}}},
                         {"boxes", nlohmann::json::array()}};
    for (size_t b = 0; b < r.boxes.size(); ++b) {
      const testing::GroundTruthBox& g = r.boxes[b];
      gt["boxes"].push_back({{"id", b + 1},
                             {"target", g.target},
                             {"dims", {g.dims.l, g.dims.b, g.dims.h}},
                             {"dims_name", g.target ? a.box : std::string("distractor")},
                             {"T_cam_box", Matrix(g.camera_T_box)},
                             {"visib_fract", g.visib_fract},
                             {"grasp_face", BoxFaceName(g.grasp_face)},
                             {"pickable", g.pickable}});
    }
    std::ofstream(base + ".json") << gt.dump(1) << "\n";
    nlohmann::json files = {{"gt", id + ".json"}, {"depth_png", id + ".png"}};
    if (a.color) files["color_png"] = id + ".color.png";
    if (a.pcd) files["pcd"] = id + ".pcd";
    index["scenes"].push_back({{"scene_id", id}, {"type", type}, {"files", files}});
    std::printf("%s: %zu boxes, %d valid px\n", id.c_str(), r.boxes.size(), r.stats.valid);
  }
  std::ofstream(a.out + "/index.json") << index.dump(1) << "\n";
  std::ofstream(a.out + "/intrinsics.txt")
      << camera.width << "," << camera.height << "," << camera.fx << "," << camera.fy << ","
      << camera.cx << "," << camera.cy << "\n";
  return 0;
}

bool ParseResolution(const std::string& text, int* width, int* height) {
  const std::vector<std::string> parts = absl::StrSplit(text, 'x');
  return parts.size() == 2 && absl::SimpleAtoi(parts[0], width) &&
         absl::SimpleAtoi(parts[1], height) && *width > 0 && *height > 0;
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
    } else if (k == "--color") {
      a.color = true;
    } else if (k == "--out" && has_value) {
      a.out = argv[++i];
    } else if (k == "--kind" && has_value) {
      a.kind = argv[++i];
    } else if (k == "--box" && has_value) {
      a.box = argv[++i];
    } else if (k == "--sensor" && has_value) {
      a.sensor = argv[++i];
    } else if (k == "--resolution" && has_value &&
               cornerpose::ParseResolution(argv[i + 1], &a.width, &a.height)) {
      ++i;
    } else if (k == "--count" && has_value && absl::SimpleAtoi(argv[i + 1], &a.count)) {
      ++i;
    } else if (k == "--seed" && has_value && absl::SimpleAtoi(argv[i + 1], &a.seed)) {
      ++i;
    } else if (k == "--take_every" && has_value && absl::SimpleAtoi(argv[i + 1], &a.take_every) &&
               a.take_every > 0) {
      ++i;
    } else {
      std::fprintf(stderr,
                   "usage: make_frames --out DIR "
                   "[--kind isolated|heap|pallet|touching|cell|mixed|depal] [--count N] "
                   "[--seed S] [--box NAME|L,B,H] [--sensor kinect|tof|stereo] "
                   "[--resolution WxH] [--color] [--pcd] [--take_every N]\n");
      return 2;
    }
  }
  if (a.out.empty() || a.count < 1) {
    std::fprintf(stderr, "make_frames: --out is required and --count must be positive\n");
    return 2;
  }
  return cornerpose::Run(a);
}
