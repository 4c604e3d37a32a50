#include "common/viz/detection_ply.h"

#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/viz/box_wireframe.h"

namespace cornerpose {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the PLY writer copies floats as they lie in memory");

using Rgb = std::array<uint8_t, 3>;
constexpr Rgb kGrey = {128, 128, 128};
constexpr Rgb kRed = {255, 0, 0};
constexpr Rgb kGreen = {0, 255, 0};
constexpr Rgb kYellow = {255, 255, 0};
constexpr double kStepM = 0.001;
// A line longer than this (a broken pose, a stray segment) is sampled more
// sparsely rather than filling the file.
constexpr int kMaxSamplesPerLine = 20000;
constexpr double kCrossHalfM = 0.005;

// Segment k's shade: blue with a green share that steps through 256 values,
// so neighbouring segments differ.
Rgb SegmentColour(size_t k) { return {0, static_cast<uint8_t>((k * 97 + 40) % 256), 255}; }

class PlyPoints {
 public:
  void Add(const Eigen::Vector3d& p, const Rgb& colour) {
    if (!p.allFinite()) return;
    std::array<uint8_t, 15> record;
    const float xyz[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                          static_cast<float>(p.z())};
    std::memcpy(record.data(), xyz, 12);
    std::memcpy(record.data() + 12, colour.data(), 3);
    bytes_.insert(bytes_.end(), record.begin(), record.end());
  }
  void Line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Rgb& colour) {
    if (!a.allFinite() || !b.allFinite()) return;
    const double length = (b - a).norm();
    const int steps =
        static_cast<int>(std::min<double>(std::ceil(length / kStepM), kMaxSamplesPerLine));
    for (int i = 0; i <= steps; ++i)
      Add(a + (b - a) * (steps == 0 ? 0.0 : double(i) / steps), colour);
  }
  size_t size() const { return bytes_.size() / 15; }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

struct FileCloser {
  void operator()(FILE* f) const {
    if (f != nullptr) std::fclose(f);
  }
};

absl::Status WriteError(const std::string& path, const char* what) {
  const int err = errno;
  const std::string message = absl::StrCat(path, ": ", what);
  return err != 0 ? absl::ErrnoToStatus(err, message) : absl::DataLossError(message);
}

}  // namespace

absl::Status WriteDetectionPly(const std::string& path, const PointCloud& cloud,
                               const Detection& detection, const BoxDims& dims) {
  if (absl::Status s = cloud.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not written: ", s.message()));
  }
  PlyPoints points;
  for (const Eigen::Vector3f& p : cloud.xyz) {
    if (PointCloud::IsValid(p)) points.Add(p.cast<double>(), kGrey);
  }
  for (const Eigen::Vector3f& p : detection.edge_points) points.Add(p.cast<double>(), kRed);
  for (size_t k = 0; k < detection.segments.size(); ++k) {
    const EdgeSegment& s = detection.segments[k];
    points.Line(s.end1.cast<double>(), s.end2.cast<double>(), SegmentColour(k));
  }
  for (const DetectedBox& box : detection.boxes) {
    const std::array<Eigen::Vector3d, 8> corners = BoxCornersCamera(box.camera_T_box, dims);
    for (const auto& [i, j] : BoxEdges()) points.Line(corners[i], corners[j], kGreen);
  }
  for (const Corner& c : detection.corners) {
    const Eigen::Vector3d centre = c.position.cast<double>();
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d half = kCrossHalfM * Eigen::Vector3d::Unit(axis);
      points.Line(centre - half, centre + half, kYellow);
    }
  }

  std::unique_ptr<FILE, FileCloser> fp(std::fopen(path.c_str(), "wb"));
  if (fp == nullptr) return WriteError(path, "cannot open for writing");
  const std::string header = absl::StrCat(
      "ply\nformat binary_little_endian 1.0\n"
      "comment cornerpose detection: grey cloud, red edge points, blue/cyan segments, "
      "green boxes, yellow corners\n"
      "element vertex ",
      points.size(),
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n");
  bool ok = std::fwrite(header.data(), 1, header.size(), fp.get()) == header.size();
  ok = ok && std::fwrite(points.bytes().data(), 1, points.bytes().size(), fp.get()) ==
                 points.bytes().size();
  ok = (std::fclose(fp.release()) == 0) && ok;
  if (!ok) return WriteError(path, "write failed");
  return absl::OkStatus();
}

}  // namespace cornerpose
