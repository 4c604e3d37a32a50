#include "common/perception/layer_turn.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "common/perception/internal/grasp_face.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// `deg` brought into [-45, 45] degrees: a box's turn is known mod 90 (its
// face's sides are its axes either way).
double Quarter(double deg) { return std::remainder(deg, 90.0); }

// The turn about `n` that takes direction `from` onto `to` (both in the
// plane of n), mod 90 degrees.
double TurnDeg(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& n) {
  const Eigen::Vector3d f = (from - from.dot(n) * n).normalized();
  const Eigen::Vector3d t = (to - to.dot(n) * n).normalized();
  return Quarter(std::atan2(f.cross(t).dot(n), f.dot(t)) / kDeg);
}

// Of the neighbours' turns (mod 90), the largest set within agree_deg of
// one of them, as turns near that one (unwrapped); empty when none.
std::vector<double> LargestAgreeing(const std::vector<double>& turns, double agree_deg) {
  std::vector<double> best;
  for (double seed : turns) {
    std::vector<double> near;
    for (double t : turns) {
      const double d = Quarter(t - seed);
      if (std::abs(d) <= agree_deg) near.push_back(seed + d);
    }
    if (near.size() > best.size()) best = std::move(near);
  }
  return best;
}

}  // namespace

absl::Status LayerTurnOptions::Validate() const {
  for (absl::Status s : {CheckRange("layer_turn.min_agreeing", min_agreeing, 0, 100),
                         CheckPositive("layer_turn.agree_deg", agree_deg, 10.0),
                         CheckRange("layer_turn.min_turn_deg", min_turn_deg, 0.0, 45.0),
                         CheckRange("layer_turn.max_turn_deg", max_turn_deg, 0.0, 45.0),
                         CheckRange("layer_turn.max_normal_deg", max_normal_deg, 0.0, 30.0),
                         CheckPositive("layer_turn.plane_tolerance_m", plane_tolerance_m, 0.1),
                         CheckPositive("layer_turn.touch_factor", touch_factor, 2.0)}) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

int AlignToLayerTurns(const BoxDims& dims, const LayerTurnOptions& options,
                      std::vector<DetectedBox>* boxes) {
  const int n = static_cast<int>(boxes->size());
  if (options.min_agreeing <= 0 || n <= options.min_agreeing) return 0;
  const double cos_max = std::cos(options.max_normal_deg * kDeg);
  std::vector<internal::GraspFace> faces;
  faces.reserve(n);
  for (const DetectedBox& box : *boxes) faces.push_back(internal::GraspFaceOf(box, dims));
  // Every box's turn from the boxes as returned, applied at the end: the
  // order of the boxes does not matter.
  std::vector<std::optional<double>> turn(n);
  for (int i = 0; i < n; ++i) {
    const internal::GraspFace& fi = faces[i];
    std::vector<double> turns;
    for (int j = 0; j < n; ++j) {
      if (j == i || !internal::FacesOnOnePlane(fi, faces[j], cos_max, options.plane_tolerance_m) ||
          !internal::FacesTouch(fi, faces[j], options.touch_factor)) {
        continue;
      }
      turns.push_back(TurnDeg(fi.a, faces[j].a, fi.n));
    }
    std::vector<double> layer = LargestAgreeing(turns, options.agree_deg);
    if (static_cast<int>(layer.size()) < options.min_agreeing) continue;
    // Its own turn (0) counts too, brought near the layer's.
    layer.push_back(Quarter(0.0 - layer.front()) + layer.front());
    std::sort(layer.begin(), layer.end());
    const size_t mid = layer.size() / 2;
    const double median =
        Quarter(layer.size() % 2 == 1 ? layer[mid] : 0.5 * (layer[mid - 1] + layer[mid]));
    if (std::abs(median) > options.min_turn_deg && std::abs(median) <= options.max_turn_deg) {
      turn[i] = median;
    }
  }
  int turned = 0;
  for (int i = 0; i < n; ++i) {
    if (!turn[i]) continue;
    DetectedBox& box = (*boxes)[i];
    const Eigen::Matrix3d r = Eigen::AngleAxisd(*turn[i] * kDeg, faces[i].n).toRotationMatrix();
    box.camera_T_box.linear() = r * box.camera_T_box.linear();
    box.camera_T_box.translation() = faces[i].c + r * (box.camera_T_box.translation() - faces[i].c);
    ++turned;
  }
  return turned;
}

}  // namespace cornerpose
