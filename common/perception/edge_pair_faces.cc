#include "common/perception/edge_pair_faces.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/perception/box_pose.h"
#include "common/validation/range_check.h"

namespace cornerpose {

absl::Status EdgePairOptions::Validate() const {
  for (absl::Status s : {
           CheckRange("edge_pairs.max_angle_deg", max_angle_deg, 0.0, 45.0),
           CheckPositive("edge_pairs.width_tolerance_m", width_tolerance_m, 1.0),
           CheckRange("edge_pairs.min_length_m", min_length_m, 0.0, 10.0),
           CheckRange("edge_pairs.min_overlap", min_overlap, 0.0, 1.0),
           CheckRange("edge_pairs.length_tolerance_m", length_tolerance_m, 0.0, 1.0),
       }) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

std::vector<EdgePairFace> ProposeFromEdgePairs(const std::vector<EdgeSegment>& segments,
                                               const BoxDims& dims, const EdgePairOptions& o) {
  std::vector<EdgePairFace> out;
  if (!o.enabled) return out;
  const double cos_max = std::cos(o.max_angle_deg * std::numbers::pi / 180.0);
  const int n = static_cast<int>(segments.size());
  for (int i = 0; i < n; ++i) {
    const EdgeSegment& si = segments[i];
    const double len_i = si.length();
    if (!(len_i >= o.min_length_m && std::isfinite(len_i))) continue;  // NaN fails too
    const Eigen::Vector3d a0 = si.end1.cast<double>(), a1 = si.end2.cast<double>();
    const Eigen::Vector3d di = (a1 - a0) / len_i;
    for (int j = i + 1; j < n; ++j) {
      const EdgeSegment& sj = segments[j];
      const double len_j = sj.length();
      if (!(len_j >= o.min_length_m && std::isfinite(len_j))) continue;
      Eigen::Vector3d b0 = sj.end1.cast<double>(), b1 = sj.end2.cast<double>();
      Eigen::Vector3d dj = (b1 - b0) / len_j;
      if (di.dot(dj) < 0.0) {
        std::swap(b0, b1);
        dj = -dj;
      }
      if (di.dot(dj) < cos_max) continue;
      const Eigen::Vector3d u = (di + dj).normalized();
      // Across: from segment i's middle to segment j's, less the part along u.
      const Eigen::Vector3d mi = (a0 + a1) / 2.0, mj = (b0 + b1) / 2.0;
      Eigen::Vector3d across = (mj - mi) - (mj - mi).dot(u) * u;
      const double width = across.norm();
      if (width < 1e-3) continue;
      const Eigen::Vector3d v = across / width;
      // Both of j's ends that far from i (not a skew pair).
      auto off = [&](const Eigen::Vector3d& p) {
        const Eigen::Vector3d d = p - mi;
        return (d - d.dot(u) * u).norm();
      };
      // Where each segment runs along u, from segment i's middle.
      const double ta0 = (a0 - mi).dot(u), ta1 = (a1 - mi).dot(u);
      const double tb0 = (b0 - mi).dot(u), tb1 = (b1 - mi).dot(u);
      const double overlap = std::min(ta1, tb1) - std::max(ta0, tb0);
      if (overlap < o.min_overlap * std::min(len_i, len_j)) continue;
      const double lo = std::min(ta0, tb0), hi = std::max(ta1, tb1);
      for (int across_axis = 0; across_axis < 3; ++across_axis) {
        const double w = dims[across_axis];
        if (std::abs(width - w) > o.width_tolerance_m ||
            std::abs(off(b0) - w) > 2.0 * o.width_tolerance_m ||
            std::abs(off(b1) - w) > 2.0 * o.width_tolerance_m) {
          continue;
        }
        for (int along_axis = 0; along_axis < 3; ++along_axis) {
          if (along_axis == across_axis) continue;
          const double l = dims[along_axis];
          if (std::max(len_i, len_j) > l + o.length_tolerance_m) continue;
          // The face's corner on segment i's side (the face centred
          // between the two lines), anchored at each end of their span.
          AxisAssignment as;
          as.axis1 = along_axis;
          as.axis2 = across_axis;
          double starts[2] = {lo, hi - l};
          const int count = std::abs(starts[1] - starts[0]) < 0.01 ? 1 : 2;
          if (count == 1) starts[0] = (lo + hi - l) / 2.0;
          for (int k = 0; k < count; ++k) {
            const Eigen::Vector3d p1 = mi + starts[k] * u + (width - w) / 2.0 * v;
            out.push_back({PoseFromCorner(p1, u, v, as, dims), i, j});
          }
        }
      }
    }
  }
  return out;
}

}  // namespace cornerpose
