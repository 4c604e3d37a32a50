#include "common/perception/box_pose.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace cornerpose {

absl::Status PoseOptions::Validate() const {
  if (!(length_tolerance_m > 0.0 && length_tolerance_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("length_tolerance_m=", length_tolerance_m, " is outside (0, 0.5] m"));
  }
  if (!(min_occluded_fraction >= 0.0 && min_occluded_fraction <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("min_occluded_fraction=", min_occluded_fraction, " is outside [0, 1]"));
  }
  if (!(corner_match_m > 0.0 && corner_match_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("corner_match_m=", corner_match_m, " is outside (0, 0.5] m"));
  }
  if (max_readings_per_corner < 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "max_readings_per_corner=", max_readings_per_corner, " is negative (0: every reading)"));
  }
  return absl::OkStatus();
}

namespace {

// Cost of reading a measured edge as a given side; negative when impossible.
double EdgeCost(double length, double side, const PoseOptions& o) {
  const double diff = length - side;
  if (std::abs(diff) <= o.length_tolerance_m) return std::abs(diff) / o.length_tolerance_m;
  if (diff < 0.0) {  // shorter: partly hidden
    return length >= o.min_occluded_fraction * side ? 1.0 + (-diff / side) : -1.0;
  }
  return o.allow_run_on ? 2.0 + diff / side : -1.0;  // longer: runs on into a neighbour
}

}  // namespace

std::vector<AxisAssignment> MatchEdgeLengths(double length1, double length2, const BoxDims& dims,
                                             const PoseOptions& options) {
  std::vector<AxisAssignment> out;
  for (int a1 = 0; a1 < 3; ++a1) {
    for (int a2 = 0; a2 < 3; ++a2) {
      if (a1 == a2) continue;
      const double c1 = EdgeCost(length1, dims[a1], options);
      const double c2 = EdgeCost(length2, dims[a2], options);
      if (c1 < 0.0 || c2 < 0.0) continue;
      out.push_back({a1, a2, c1 + c2});
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const AxisAssignment& x, const AxisAssignment& y) {
    return x.length_cost < y.length_cost;
  });
  return out;
}

std::vector<AxisAssignment> CheapestReadings(std::vector<AxisAssignment> readings,
                                             int max_readings) {
  if (max_readings <= 0 || static_cast<int>(readings.size()) <= max_readings) return readings;
  // Ties with the last kept stay: which of two equal readings goes would
  // depend on the order the axes are tried in.
  const double last = readings[max_readings - 1].length_cost;
  size_t keep = max_readings;
  while (keep < readings.size() && readings[keep].length_cost <= last + 1e-12) ++keep;
  readings.resize(keep);
  return readings;
}

Eigen::Isometry3d PoseFromCorner(const Eigen::Vector3d& p1, const Eigen::Vector3d& d1_in,
                                 const Eigen::Vector3d& d2_in, const AxisAssignment& assignment,
                                 const BoxDims& dims) {
  const Eigen::Vector3d d1 = d1_in.normalized();
  const Eigen::Vector3d d2 = (d2_in - d2_in.dot(d1) * d1).normalized();
  // eq. 4-5: d = d1 x d2 must face the camera (d . t > 0).
  const Eigen::Vector3d t = -p1.normalized();
  Eigen::Vector3d d = d1.cross(d2);
  if (d.dot(t) < 0.0) d = -d;
  const int i = assignment.axis1, j = assignment.axis2, k = 3 - i - j;
  // Box axis i along +d1 (or -d1), j along +d2 (or -d2), k along d. Of the
  // four sign choices two are right-handed, and they differ by a half-turn
  // about k, a symmetry of the box: take the first (Table 1).
  Eigen::Matrix3d R;
  double s1 = 1.0, s2 = 1.0;
  R.col(i) = d1;
  R.col(j) = d2;
  R.col(k) = d;
  if (R.determinant() < 0.0) {
    s2 = -1.0;
    R.col(j) = -d2;
  }
  // p1 sits at -s*side/2 along each edge axis (the edges run from it into the
  // box) and on the face toward the camera (+side/2 along k).
  Eigen::Vector3d corner_in_box;
  corner_in_box[i] = -s1 * dims[i] / 2.0;
  corner_in_box[j] = -s2 * dims[j] / 2.0;
  corner_in_box[k] = dims[k] / 2.0;
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  camera_T_box.linear() = R;
  camera_T_box.translation() = p1 - R * corner_in_box;
  return camera_T_box;
}

std::array<Eigen::Vector3d, 8> BoxCorners(const Eigen::Isometry3d& camera_T_box,
                                          const BoxDims& dims) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d local((c & 1 ? 0.5 : -0.5) * dims.l, (c & 2 ? 0.5 : -0.5) * dims.b,
                                (c & 4 ? 0.5 : -0.5) * dims.h);
    corners[c] = camera_T_box * local;
  }
  return corners;
}

int RefineWithCorners(const std::vector<Eigen::Vector3d>& observed_corners, const BoxDims& dims,
                      const PoseOptions& options, Eigen::Isometry3d* camera_T_box) {
  const std::array<Eigen::Vector3d, 8> predicted = BoxCorners(*camera_T_box, dims);
  const Eigen::Isometry3d box_T_camera = camera_T_box->inverse();
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;  // (model, observed)
  std::array<bool, 8> used{};
  for (const Eigen::Vector3d& o : observed_corners) {
    int best = -1;
    double best_d = options.corner_match_m;
    for (int c = 0; c < 8; ++c) {
      const double d = (predicted[c] - o).norm();
      if (!used[c] && d < best_d) {
        best_d = d;
        best = c;
      }
    }
    if (best < 0) continue;
    used[best] = true;
    pairs.emplace_back(box_T_camera * predicted[best], o);
  }
  if (pairs.size() < 3) return 0;
  Eigen::Matrix3Xd src(3, pairs.size()), dst(3, pairs.size());
  for (size_t n = 0; n < pairs.size(); ++n) {
    src.col(n) = pairs[n].first;
    dst.col(n) = pairs[n].second;
  }
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, /*with_scaling=*/false);
  // Three nearly collinear corners leave the rotation about their line free.
  Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(dst.colwise() - dst.rowwise().mean());
  if (svd.singularValues()(1) < 1e-3) return 0;
  camera_T_box->matrix() = T;
  return static_cast<int>(pairs.size());
}

}  // namespace cornerpose
