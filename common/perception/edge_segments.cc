#include "common/perception/edge_segments.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "common/perception/internal/parallel.h"

namespace cornerpose {
namespace {

struct Line {
  Eigen::Vector3f point = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitX();  // unit
  float Distance2(const Eigen::Vector3f& p) const {
    const Eigen::Vector3f d = p - point;
    return (d - d.dot(direction) * direction).squaredNorm();
  }
  float T(const Eigen::Vector3f& p) const { return (p - point).dot(direction); }
};

// Least-squares line through points (principal axis).
Line FitLine(const std::vector<Eigen::Vector3f>& pts, const std::vector<int>& idx) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : idx) mean += pts[i].cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : idx) {
    const Eigen::Vector3d d = pts[i].cast<double>() - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Line line;
  line.point = mean.cast<float>();
  line.direction = eig.eigenvectors().col(2).normalized().cast<float>();
  return line;
}

// Uniform grid over the edge points, for drawing the second RANSAC sample
// near the first.
class Grid {
 public:
  Grid(const std::vector<Eigen::Vector3f>& pts, float cell) : cell_(cell) {
    for (int i = 0; i < static_cast<int>(pts.size()); ++i) cells_[Key(pts[i])].push_back(i);
  }
  template <typename Fn>
  void ForNear(const Eigen::Vector3f& p, Fn&& fn) const {
    const int cx = Coord(p.x()), cy = Coord(p.y()), cz = Coord(p.z());
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = cells_.find(Pack(cx + dx, cy + dy, cz + dz));
          if (it == cells_.end()) continue;
          for (int i : it->second) fn(i);
        }
  }

 private:
  int Coord(float v) const { return static_cast<int>(std::floor(v / cell_)); }
  static int64_t Pack(int x, int y, int z) {
    return (static_cast<int64_t>(x & 0x1FFFFF) << 42) | (static_cast<int64_t>(y & 0x1FFFFF) << 21) |
           static_cast<int64_t>(z & 0x1FFFFF);
  }
  int64_t Key(const Eigen::Vector3f& p) const {
    return Pack(Coord(p.x()), Coord(p.y()), Coord(p.z()));
  }
  float cell_;
  std::unordered_map<int64_t, std::vector<int>> cells_;
};

class SegmentFitter {
 public:
  SegmentFitter(const std::vector<Eigen::Vector3f>& pts, const EdgeSegmentOptions& o,
                internal::SharedLoops* shared, const CancelToken* cancel)
      : pts_(pts),
        options_(o),
        alive_(pts.size(), 1),
        num_alive_(static_cast<int>(pts.size())),
        grid_(pts, static_cast<float>(o.sample_max_m / 2.0)),
        rng_(o.seed),
        shared_(shared),
        cancel_(cancel),
        pool_(shared != nullptr ? 1 : o.num_threads) {}

  std::vector<EdgeSegment> Run() {
    std::vector<EdgeSegment> segments;
    int failures = 0;
    while (num_alive_ >= options_.min_points &&
           static_cast<int>(segments.size()) < options_.max_segments &&
           failures < options_.max_failures && !StopRequested(cancel_)) {
      std::optional<Line> line = BestHypothesis();
      if (!line) break;
      std::optional<EdgeSegment> segment = ExtractRun(*line);
      if (segment) {
        segments.push_back(*segment);
        failures = 0;
      } else {
        ++failures;
      }
    }
    return segments;
  }

 private:
  std::vector<int> AliveIndices() const {
    std::vector<int> idx;
    idx.reserve(num_alive_);
    for (int i = 0; i < static_cast<int>(pts_.size()); ++i)
      if (alive_[i]) idx.push_back(i);
    return idx;
  }

  std::optional<Line> BestHypothesis() {
    std::vector<int> alive = AliveIndices();
    if (alive.size() < 2) return std::nullopt;
    std::vector<int> subset = alive;
    if (static_cast<int>(subset.size()) > options_.ransac_subset) {
      // A uniform random subset: the first ransac_subset of a partial
      // Fisher-Yates shuffle.
      for (int i = 0; i < options_.ransac_subset; ++i) {
        const int j =
            std::uniform_int_distribution<int>(i, static_cast<int>(subset.size()) - 1)(rng_);
        std::swap(subset[i], subset[j]);
      }
      subset.resize(options_.ransac_subset);
    }
    const float t2 = static_cast<float>(options_.ransac_threshold_m * options_.ransac_threshold_m);
    const float min2 = static_cast<float>(options_.sample_min_m * options_.sample_min_m);
    const float max2 = static_cast<float>(options_.sample_max_m * options_.sample_max_m);
    // The subset as structure of arrays: the count below is the stage's
    // inner loop (iterations x subset), and in this layout it vectorizes.
    sx_.resize(subset.size());
    sy_.resize(subset.size());
    sz_.resize(subset.size());
    for (size_t k = 0; k < subset.size(); ++k) {
      sx_[k] = pts_[subset[k]].x();
      sy_[k] = pts_[subset[k]].y();
      sz_[k] = pts_[subset[k]].z();
    }
    // The random draws first, in order (two per iteration: the first point,
    // and where among its candidates the second lies), so the iterations can
    // run on any thread and the result does not depend on which.
    const int iterations = options_.ransac_iterations;
    std::vector<int> first(iterations);
    std::vector<float> second(iterations);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(alive.size()) - 1);
    std::uniform_real_distribution<float> where(0.0f, 1.0f);
    for (int it = 0; it < iterations; ++it) {
      first[it] = alive[pick(rng_)];
      second[it] = where(rng_);
    }
    std::vector<int> counts(iterations, -1);
    std::vector<Line> lines(iterations);
    auto iterate = [&](int begin, int end) {
      std::vector<int> candidates;
      for (int it = begin; it < end; ++it) {
        const int a = first[it];
        candidates.clear();
        grid_.ForNear(pts_[a], [&](int i) {
          if (!alive_[i]) return;
          const float d2 = (pts_[i] - pts_[a]).squaredNorm();
          if (d2 >= min2 && d2 <= max2) candidates.push_back(i);
        });
        if (candidates.empty()) continue;
        const size_t k =
            std::min(candidates.size() - 1, static_cast<size_t>(second[it] * candidates.size()));
        lines[it].point = pts_[a];
        lines[it].direction = (pts_[candidates[k]] - pts_[a]).normalized();
        counts[it] = CountWithin(lines[it], t2);
      }
    };
    // Chunks of 8 iterations: ~15 per loop, enough to share with a helper
    // that joins late.
    if (shared_ != nullptr) {
      shared_->Run(iterations, 8, iterate);
    } else {
      pool_.Run(iterations, [&](int, int begin, int end) { iterate(begin, end); });
    }
    std::optional<Line> best;
    int best_count = 0;
    for (int it = 0; it < iterations; ++it) {
      if (counts[it] > best_count) {
        best_count = counts[it];
        best = lines[it];
      }
    }
    return best;
  }

  // Subset points within sqrt(t2) of the line: Line::Distance2 written out
  // in the same order of operations, so the counts are the same.
  int CountWithin(const Line& line, float t2) const {
    const float px = line.point.x(), py = line.point.y(), pz = line.point.z();
    const float dx = line.direction.x(), dy = line.direction.y(), dz = line.direction.z();
    const size_t n = sx_.size();
    const float* xs = sx_.data();
    const float* ys = sy_.data();
    const float* zs = sz_.data();
    int count = 0;
    for (size_t k = 0; k < n; ++k) {
      const float ax = xs[k] - px, ay = ys[k] - py, az = zs[k] - pz;
      const float t = ax * dx + ay * dy + az * dz;
      const float ex = ax - t * dx, ey = ay - t * dy, ez = az - t * dz;
      count += (ex * ex + ey * ey + ez * ez) <= t2;
    }
    return count;
  }

  std::vector<int> Inliers(const Line& line, float threshold) const {
    const float t2 = threshold * threshold;
    std::vector<int> idx;
    for (int i = 0; i < static_cast<int>(pts_.size()); ++i)
      if (alive_[i] && line.Distance2(pts_[i]) <= t2) idx.push_back(i);
    return idx;
  }

  // Reference point, Algorithm 1 extremities, removal. Returns the segment
  // when it is long and dense enough; its points are removed either way.
  std::optional<EdgeSegment> ExtractRun(Line line) {
    const float threshold = static_cast<float>(options_.ransac_threshold_m);
    std::vector<int> inliers = Inliers(line, threshold);
    if (inliers.size() >= 2) {
      line = FitLine(pts_, inliers);
      inliers = Inliers(line, threshold);
    }
    if (inliers.empty()) {
      // Degenerate hypothesis: retire the seed region so the loop progresses.
      return std::nullopt;
    }
    std::vector<Eigen::Vector3f> run_pts;
    run_pts.reserve(inliers.size());
    for (int i : inliers) run_pts.push_back(pts_[i]);
    const int reference = ReferenceIndex(line, run_pts);
    const auto [e1, e2] = FindExtremities(run_pts, reference, options_.gap_m);
    float t1 = line.T(run_pts[e1]), t2 = line.T(run_pts[e2]);
    if (t1 > t2) std::swap(t1, t2);

    std::vector<int> run;
    for (int i : inliers) {
      const float t = line.T(pts_[i]);
      if (t >= t1 && t <= t2) run.push_back(i);
    }
    if (run.size() >= 2) line = FitLine(pts_, run);
    // Re-derive the ends on the refitted line.
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    for (int i : run) {
      const float t = line.T(pts_[i]);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    // Remove the run with a tube wider than the RANSAC one (edge bands).
    const float removal = threshold * static_cast<float>(options_.removal_scale);
    const float r2 = removal * removal;
    int removed = 0;
    for (int i = 0; i < static_cast<int>(pts_.size()); ++i) {
      if (!alive_[i]) continue;
      const float t = line.T(pts_[i]);
      if (t >= lo && t <= hi && line.Distance2(pts_[i]) <= r2) {
        alive_[i] = 0;
        ++removed;
      }
    }
    for (int i : run) {
      if (alive_[i]) {
        alive_[i] = 0;
        ++removed;
      }
    }
    if (removed == 0) {
      alive_[inliers[reference]] = 0;
      removed = 1;
    }
    num_alive_ -= removed;
    if (static_cast<int>(run.size()) < options_.min_points || hi - lo < options_.min_length_m) {
      return std::nullopt;
    }
    EdgeSegment s;
    s.point = line.point;
    s.direction = line.direction;
    s.end1 = line.point + lo * line.direction;
    s.end2 = line.point + hi * line.direction;
    s.num_points = static_cast<int>(run.size());
    return s;
  }

  // The inlier with the most inliers within r_s: all inliers lie within the
  // RANSAC tube, so counting along the line over a sorted projection gives
  // the neighbour counts in O(n log n).
  int ReferenceIndex(const Line& line, const std::vector<Eigen::Vector3f>& run_pts) const {
    std::vector<std::pair<float, int>> t(run_pts.size());
    for (size_t i = 0; i < run_pts.size(); ++i) t[i] = {line.T(run_pts[i]), static_cast<int>(i)};
    std::sort(t.begin(), t.end());
    const float r = static_cast<float>(options_.gap_m);
    int best = t[t.size() / 2].second, best_count = -1;
    size_t lo = 0, hi = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      while (t[lo].first < t[i].first - r) ++lo;
      while (hi < t.size() && t[hi].first <= t[i].first + r) ++hi;
      const int count = static_cast<int>(hi - lo);
      if (count > best_count) {
        best_count = count;
        best = t[i].second;
      }
    }
    return best;
  }

  const std::vector<Eigen::Vector3f>& pts_;
  const EdgeSegmentOptions& options_;
  std::vector<uint8_t> alive_;
  int num_alive_;
  Grid grid_;
  std::mt19937 rng_;
  std::vector<float> sx_, sy_, sz_;  // the current RANSAC subset
  internal::SharedLoops* const shared_;  // null: pool_ runs the iterations
  const CancelToken* const cancel_;      // checked once per RANSAC round
  internal::ForkJoin pool_;
};

}  // namespace

absl::Status EdgeSegmentOptions::Validate() const {
  auto range = [](const char* name, double v, double lo, double hi) -> absl::Status {
    if (!(v >= lo && v <= hi)) {
      return absl::InvalidArgumentError(
          absl::StrCat("segment ", name, "=", v, " is outside [", lo, ", ", hi, "]"));
    }
    return absl::OkStatus();
  };
  for (absl::Status s :
       {range("ransac_threshold_m", ransac_threshold_m, 1e-4, 0.2),
        range("gap_m", gap_m, 1e-4, 0.5), range("ransac_iterations", ransac_iterations, 1, 100000),
        range("ransac_subset", ransac_subset, 10, 10000000),
        range("sample_min_m", sample_min_m, 0.0, 1.0),
        range("sample_max_m", sample_max_m, sample_min_m + 1e-4, 2.0),
        range("min_points", min_points, 2, 1000000), range("min_length_m", min_length_m, 0.0, 10.0),
        range("removal_scale", removal_scale, 1.0, 10.0),
        range("max_segments", max_segments, 1, 100000),
        range("max_failures", max_failures, 1, 100000),
        range("num_threads", num_threads, 1, 256)}) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

std::pair<int, int> FindExtremities(const std::vector<Eigen::Vector3f>& points, int reference,
                                    double radius_m) {
  const int n = static_cast<int>(points.size());
  if (n == 0 || reference < 0 || reference >= n) return {reference, reference};
  // Sort along the principal axis so each point's neighbours are a window.
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  const Line axis = n >= 2 ? FitLine(points, all) : Line{points[0], Eigen::Vector3f::UnitX()};
  std::vector<std::pair<float, int>> order(n);
  for (int i = 0; i < n; ++i) order[i] = {axis.T(points[i]), i};
  std::sort(order.begin(), order.end());
  const float r = static_cast<float>(radius_m), r2 = r * r;
  const Eigen::Vector3f& pr = points[reference];
  const float t_ref = axis.T(pr);

  // Extremity candidates with their distance and direction to the reference.
  struct Candidate {
    int index;
    float distance;
    Eigen::Vector3f direction;  // unit, from the point to the reference
  };
  std::vector<Candidate> candidates;
  for (int k = 0; k < n; ++k) {
    const int i = order[k].second;
    if (i == reference) continue;
    const Eigen::Vector3f d1 = pr - points[i];
    bool extreme = true;
    for (int dir : {-1, 1}) {
      for (int m = k + dir; m >= 0 && m < n && std::abs(order[m].first - order[k].first) <= r;
           m += dir) {
        const Eigen::Vector3f d2 = points[order[m].second] - points[i];
        if (d2.squaredNorm() > r2 || d2.squaredNorm() == 0.0f) continue;
        // The paper's d1 . d2 < 0, taken along the line: the points lie in
        // the RANSAC tube, and across it a neighbour beside the query point
        // would tip the sign either way.
        if ((order[m].first - order[k].first) * (t_ref - order[k].first) < 0.0f) {
          extreme = false;
          break;
        }
      }
      if (!extreme) break;
    }
    if (extreme) candidates.push_back({i, d1.norm(), d1.normalized()});
  }
  if (candidates.empty()) return {reference, reference};
  const Candidate* e1 = &candidates[0];
  for (const Candidate& c : candidates)
    if (c.distance < e1->distance) e1 = &c;
  const Candidate* e2 = nullptr;
  for (const Candidate& c : candidates) {
    if (c.direction.dot(e1->direction) >= 0.0f) continue;
    if (e2 == nullptr || c.distance < e2->distance) e2 = &c;
  }
  return {e1->index, e2 != nullptr ? e2->index : reference};
}

absl::StatusOr<std::vector<EdgeSegment>> FitEdgeSegments(
    const std::vector<Eigen::Vector3f>& edge_points, const EdgeSegmentOptions& options,
    internal::SharedLoops* shared, const CancelToken* cancel) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  SegmentFitter fitter(edge_points, options, shared, cancel);
  return fitter.Run();
}

}  // namespace cornerpose
