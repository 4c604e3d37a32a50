#include "common/perception/clubbing.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

absl::Status ClubbingOptions::Validate() const {
  if (!(perpendicular_tolerance_deg >= 0.0 && perpendicular_tolerance_deg <= 45.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "perpendicular_tolerance_deg=", perpendicular_tolerance_deg, " is outside [0, 45]"));
  }
  if (!(meet_distance_m > 0.0 && meet_distance_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("meet_distance_m=", meet_distance_m, " is outside (0, 0.5] m"));
  }
  if (!(meet_along_view_factor >= 1.0 && meet_along_view_factor <= 10.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("meet_along_view_factor=", meet_along_view_factor, " is outside [1, 10]"));
  }
  if (!(end_gap_m >= 0.0 && end_gap_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("end_gap_m=", end_gap_m, " is outside [0, 0.5] m"));
  }
  return absl::OkStatus();
}

bool SegmentsMeet(const std::vector<EdgeSegment>& segments, int a, int b,
                  const ClubbingOptions& options, Corner* corner) {
  const EdgeSegment& sa = segments[a];
  const EdgeSegment& sb = segments[b];
  const Eigen::Vector3d da = sa.direction.cast<double>().normalized();
  const Eigen::Vector3d db = sb.direction.cast<double>().normalized();
  const double max_cos = std::sin(options.perpendicular_tolerance_deg * std::numbers::pi / 180.0);
  const double c = da.dot(db);
  if (std::abs(c) > max_cos) return false;
  // Closest points of the two lines.
  const Eigen::Vector3d pa = sa.point.cast<double>(), pb = sb.point.cast<double>();
  const Eigen::Vector3d w = pa - pb;
  const double denom = 1.0 - c * c;
  const double d = da.dot(w), e = db.dot(w);
  const double ta = (c * e - d) / denom;
  const double tb = (e - c * d) / denom;
  const Eigen::Vector3d qa = pa + ta * da, qb = pb + tb * db;
  const Eigen::Vector3d meet = 0.5 * (qa + qb);
  const Eigen::Vector3d gap = qa - qb;
  const double view_norm = meet.norm();
  const double along_view = view_norm > 1e-9 ? gap.dot(meet) / view_norm : 0.0;
  const double across_view = std::sqrt(std::max(0.0, gap.squaredNorm() - along_view * along_view));
  if (across_view > options.meet_distance_m ||
      std::abs(along_view) > options.meet_along_view_factor * options.meet_distance_m) {
    return false;
  }
  const double a1 = (sa.end1.cast<double>() - meet).norm(),
               a2 = (sa.end2.cast<double>() - meet).norm();
  const double b1 = (sb.end1.cast<double>() - meet).norm(),
               b2 = (sb.end2.cast<double>() - meet).norm();
  if (std::min(a1, a2) > options.end_gap_m || std::min(b1, b2) > options.end_gap_m) return false;
  corner->position = meet.cast<float>();
  corner->segment_a = a;
  corner->segment_b = b;
  corner->a_at_end1 = a1 <= a2;
  corner->b_at_end1 = b1 <= b2;
  return true;
}

absl::StatusOr<SegmentGroups> ClubSegments(const std::vector<EdgeSegment>& segments,
                                           const ClubbingOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  const int n = static_cast<int>(segments.size());
  SegmentGroups out;
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      Corner corner;
      if (!SegmentsMeet(segments, a, b, options, &corner)) continue;
      out.corners.push_back(corner);
      parent[Find(parent, a)] = Find(parent, b);
    }
  }
  std::map<int, std::vector<int>> by_root;
  for (int i = 0; i < n; ++i) by_root[Find(parent, i)].push_back(i);
  for (auto& [root, members] : by_root) {
    if (members.size() >= 2) out.groups.push_back(std::move(members));
  }
  return out;
}

}  // namespace cornerpose
