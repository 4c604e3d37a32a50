#include "common/perception/edge_points.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <thread>
#include <unordered_set>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "absl/strings/str_cat.h"
#include "common/perception/internal/parallel.h"
#include "common/perception/internal/round_half_away.h"
#include "common/perception/internal/select_kth.h"

namespace cornerpose {
namespace {

// Per-thread output, merged in order so the result does not depend on timing.
struct Chunk {
  std::vector<int> indices;
  std::vector<float> scores;
};

// A sunflower (Vogel) spiral: n points spread evenly over the unit disc. Even
// coverage keeps a flat patch's score near 0 with few samples.
std::vector<Eigen::Vector2f> UnitDiscPattern(int n) {
  std::vector<Eigen::Vector2f> pattern;
  pattern.reserve(n);
  const float golden = std::numbers::pi_v<float> * (3.0f - std::sqrt(5.0f));
  for (int k = 0; k < n; ++k) {
    const float r = std::sqrt((k + 0.5f) / n);
    const float a = k * golden;
    pattern.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return pattern;
}

struct NeighbourSum {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  int count = 0;
  void Add(const Eigen::Vector3f& d, float dist2) {
    if (dist2 <= 0.0f) return;
    sum += d / std::sqrt(dist2);
    ++count;
  }
  float Score() const { return count > 0 ? sum.norm() / count : 0.0f; }
};

class OrganizedScorer {
 public:
  OrganizedScorer(const PointCloud& cloud, const EdgePointOptions& options, double focal_px)
      : cloud_(cloud),
        options_(options),
        focal_px_(static_cast<float>(focal_px)),
        radius2_(static_cast<float>(options.radius_m * options.radius_m)),
        pattern_(UnitDiscPattern(std::max(options.max_samples, 1))) {
    BuildOffsets(options.max_samples, &offsets_);
  }

  // The score of pixel (u, v), or -1 where it is not scored (no return,
  // neighbourhood cut by the frame, too few neighbours).
  float ScoreAt(int u, int v) const {
    const Eigen::Vector3f& p = cloud_.xyz[v * cloud_.width + u];
    if (!PointCloud::IsValid(p) || p.z() <= 0.0f) return -1.0f;
    const float radius_px = static_cast<float>(options_.radius_m) * focal_px_ / p.z();
    if (CutByBorder(u, v, radius_px)) return -1.0f;
    const NeighbourSum n = Neighbours(u, v, p, radius_px);
    if (n.count < options_.min_neighbours) return -1.0f;
    return n.Score();
  }

  // Coarse pass: the score of each grid cell's (cell_px x cell_px pixels)
  // centre pixel on the lattice of every `lattice` pixels, -1 where it is
  // not scored.
  void ScoreCoarse(int cell_row_begin, int cell_row_end, int cell_px, int lattice,
                   std::vector<float>* cell_scores) const {
    const int cells_w = (cloud_.width + cell_px - 1) / cell_px;
    const int centre = (cell_px / lattice / 2) * lattice;
    for (int cv = cell_row_begin; cv < cell_row_end; ++cv) {
      for (int cu = 0; cu < cells_w; ++cu) {
        const int u = std::min(cu * cell_px + centre, cloud_.width - 1);
        const int v = std::min(cv * cell_px + centre, cloud_.height - 1);
        (*cell_scores)[cv * cells_w + cu] = ScoreAt(u, v);
      }
    }
  }

  // Full-resolution pass over the rows [row_begin, row_end) of the lattice
  // of every `lattice` pixels; with `cells` (1: score the cell's pixels,
  // cells of cell_px), only those pixels are scored, and a cell's centre
  // pixel takes its score from `cell_scores` (ScoreCoarse's, the same
  // computation).
  void ScoreRows(int row_begin, int row_end, int lattice, int cell_px,
                 const std::vector<uint8_t>* cells, const std::vector<float>* cell_scores,
                 Chunk* out) const {
    const int w = cloud_.width;
    const int cells_w = (w + cell_px - 1) / cell_px;
    const int centre = (cell_px / lattice / 2) * lattice;
    for (int v = (row_begin + lattice - 1) / lattice * lattice; v < row_end; v += lattice) {
      const int cv = v / cell_px;
      const bool centre_row = v == std::min(cv * cell_px + centre, cloud_.height - 1);
      for (int u = 0; u < w; u += lattice) {
        const int cu = u / cell_px;
        if (cells != nullptr && !(*cells)[cv * cells_w + cu]) continue;
        const bool scored =
            cell_scores != nullptr && centre_row && u == std::min(cu * cell_px + centre, w - 1);
        const float score = scored ? (*cell_scores)[cv * cells_w + cu] : ScoreAt(u, v);
        if (score <= options_.threshold) continue;
        const Eigen::Vector3f& p = cloud_.xyz[v * w + u];
        const float radius_px = static_cast<float>(options_.radius_m) * focal_px_ / p.z();
        if (options_.occluded_side_jump_m > 0.0 && OnOccludedSide(u, v, p, 2.0f * radius_px)) {
          continue;
        }
        out->indices.push_back(v * w + u);
        out->scores.push_back(score);
      }
    }
  }

 private:
  static constexpr int kMaxBucket = 256;
  using OffsetTables = std::array<std::vector<int>, kMaxBucket + 1>;

  // Neighbour offsets per radius, in quarter pixels, as index deltas into
  // the row-major grid (the inner loop is then a load and a distance): the
  // whole disc, or `samples` of it on a sunflower spiral when the disc holds
  // more pixels than that (0: always the whole disc).
  void BuildOffsets(int samples, OffsetTables* tables) const {
    const std::vector<Eigen::Vector2f> pattern = UnitDiscPattern(std::max(samples, 1));
    for (int bucket = 0; bucket <= kMaxBucket; ++bucket) {
      const float radius_px = bucket / 4.0f;
      std::vector<int>& table = (*tables)[bucket];
      if (samples == 0 || std::numbers::pi_v<float> * radius_px * radius_px <= samples) {
        const int r = static_cast<int>(std::ceil(radius_px));
        for (int dv = -r; dv <= r; ++dv) {
          for (int du = -r; du <= r; ++du) {
            if ((du != 0 || dv != 0) && du * du + dv * dv <= radius_px * radius_px) {
              table.push_back(dv * cloud_.width + du);
            }
          }
        }
      } else {
        for (const Eigen::Vector2f& o : pattern) {
          const int du = static_cast<int>(std::lround(o.x() * radius_px));
          const int dv = static_cast<int>(std::lround(o.y() * radius_px));
          if (du != 0 || dv != 0) table.push_back(dv * cloud_.width + du);
        }
      }
    }
  }

  const Eigen::Vector3f* At(int u, int v) const {
    if (u < 0 || v < 0 || u >= cloud_.width || v >= cloud_.height) return nullptr;
    const Eigen::Vector3f& q = cloud_.xyz[v * cloud_.width + u];
    return PointCloud::IsValid(q) ? &q : nullptr;
  }

  // The paper's score, with one change for depth noise: the query point is
  // first moved along its ray to the median depth offset of its neighbours.
  // On a Kinect the point's own axial noise (2-4 mm) tilts every d_j the same
  // way and lifts a flat patch's score to ~0.2-0.4, so one in ten floor
  // points would pass t_h; the median offset is ~0 at a true edge.
  NeighbourSum Neighbours(int u, int v, const Eigen::Vector3f& p, float radius_px) const {
    // The neighbours as structure of arrays (per thread, sized once).
    thread_local std::vector<float> fx, fy, fz, dz, scratch;
    const float reach2 = 2.25f * radius2_;  // 1.5 r_s: room for p's own noise
    // CutByBorder() has kept the whole disc inside the image.
    // Read in place (Eigen::Vector3f is three packed floats): a copy as
    // three planes gained nothing, the gather being scalar loads either way,
    // and cost a first touch of 12 bytes a pixel, which on a VM's page
    // faults was a third of a cold frame's edge stage.
    static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
    const Eigen::Vector3f* at = cloud_.xyz.data() + static_cast<size_t>(v) * cloud_.width + u;
    // Clamped before the cast: r fx / z is unbounded for a point near z = 0.
    const float quarter_px = radius_px * 4.0f + 0.5f;
    const int bucket = quarter_px < kMaxBucket ? static_cast<int>(quarter_px) : kMaxBucket;
    const std::vector<int>& offsets = offsets_[bucket];
    // Room for a whole block of four past the last neighbour.
    if (fx.size() < offsets.size() + 4) {
      for (std::vector<float>* a : {&fx, &fy, &fz, &dz, &scratch}) a->resize(offsets.size() + 4);
    }
    // Without branches: every neighbour is written, and kept (m advances)
    // when it is within reach; a no-return (NaN) compares false.
    const float px = p.x(), py = p.y(), pz = p.z();
    size_t m = 0;
    for (const int off : offsets) {
      const float x = at[off].x(), y = at[off].y(), z = at[off].z();
      const float dx = x - px, dy = y - py, dzp = z - pz;
      fx[m] = x;
      fy[m] = y;
      fz[m] = z;
      m += (dx * dx + dy * dy) + dzp * dzp <= reach2;
    }
    Eigen::Vector3f centre = p;
    if (options_.denoise && m >= 3) {
      for (size_t k = 0; k < m; ++k) dz[k] = fz[k] - pz;
      const float median = internal::SelectKth(dz.data(), static_cast<int>(m),
                                               static_cast<int>(m / 2), scratch.data());
      centre = p * ((pz + median) / pz);
    }
    return UnitVectorSum(fx.data(), fy.data(), fz.data(), m, centre);
  }

  // The sum of the unit vectors from `centre` to the neighbours within r_s
  // (SSE: four neighbours at a time, summed in four lanes).
  NeighbourSum UnitVectorSum(const float* x, const float* y, const float* z, size_t m,
                             const Eigen::Vector3f& centre) const {
    NeighbourSum n;
    size_t k = 0;
#if defined(__SSE2__)
    const __m128 cx = _mm_set1_ps(centre.x()), cy = _mm_set1_ps(centre.y()),
                 cz = _mm_set1_ps(centre.z()), r2 = _mm_set1_ps(radius2_), zero = _mm_setzero_ps();
    __m128 sx = zero, sy = zero, sz = zero;
    int count = 0;
    for (; k + 4 <= m; k += 4) {
      const __m128 dx = _mm_sub_ps(_mm_loadu_ps(x + k), cx);
      const __m128 dy = _mm_sub_ps(_mm_loadu_ps(y + k), cy);
      const __m128 dzv = _mm_sub_ps(_mm_loadu_ps(z + k), cz);
      const __m128 d2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dzv, dzv));
      const __m128 within = _mm_and_ps(_mm_cmple_ps(d2, r2), _mm_cmpgt_ps(d2, zero));
      const __m128 inv = _mm_and_ps(within, _mm_div_ps(_mm_set1_ps(1.0f), _mm_sqrt_ps(d2)));
      sx = _mm_add_ps(sx, _mm_mul_ps(dx, inv));
      sy = _mm_add_ps(sy, _mm_mul_ps(dy, inv));
      sz = _mm_add_ps(sz, _mm_mul_ps(dzv, inv));
      // A table, not __builtin_popcount: without -mpopcnt that is a call.
      constexpr int kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
      count += kBits[_mm_movemask_ps(within)];
    }
    alignas(16) float lx[4], ly[4], lz[4];
    _mm_store_ps(lx, sx);
    _mm_store_ps(ly, sy);
    _mm_store_ps(lz, sz);
    n.sum = Eigen::Vector3f((lx[0] + lx[1]) + (lx[2] + lx[3]), (ly[0] + ly[1]) + (ly[2] + ly[3]),
                            (lz[0] + lz[1]) + (lz[2] + lz[3]));
    n.count = count;
#endif
    for (; k < m; ++k) {
      const Eigen::Vector3f d = Eigen::Vector3f(x[k], y[k], z[k]) - centre;
      const float dist2 = d.squaredNorm();
      if (dist2 <= radius2_) n.Add(d, dist2);
    }
    return n;
  }

  // True when the pixel disc of radius r around (u, v) leaves the image:
  // the neighbourhood is cut by the frame, not by the surface.
  bool CutByBorder(int u, int v, float radius_px) const {
    const int r = static_cast<int>(std::ceil(std::min(radius_px, kMaxBucket / 4.0f) + 0.25f));
    return u - r < 0 || v - r < 0 || u + r >= cloud_.width || v + r >= cloud_.height;
  }

  bool OnOccludedSide(int u, int v, const Eigen::Vector3f& p, float radius_px) const {
    // Past the image's size every offset leaves it; keeps the rounding in int.
    radius_px = std::min(radius_px, static_cast<float>(cloud_.width + cloud_.height));
    const float nearer = p.z() - static_cast<float>(options_.occluded_side_jump_m);
    for (const Eigen::Vector2f& o : pattern_) {
      const Eigen::Vector3f* q = At(u + internal::RoundHalfAway(o.x() * radius_px),
                                    v + internal::RoundHalfAway(o.y() * radius_px));
      if (q != nullptr && q->z() < nearer) return true;
    }
    return false;
  }

  const PointCloud& cloud_;
  const EdgePointOptions& options_;
  const float focal_px_;
  const float radius2_;
  const std::vector<Eigen::Vector2f> pattern_;
  // Radii above kMaxBucket / 4 pixels (points nearer than ~0.17 m for the
  // default radius and a VGA camera) use the largest table.
  OffsetTables offsets_;
};

EdgePoints Merge(const PointCloud& cloud, std::vector<Chunk>& chunks) {
  EdgePoints out;
  for (Chunk& c : chunks) {
    out.indices.insert(out.indices.end(), c.indices.begin(), c.indices.end());
    out.scores.insert(out.scores.end(), c.scores.begin(), c.scores.end());
  }
  out.points.reserve(out.indices.size());
  for (int i : out.indices) out.points.push_back(cloud.xyz[i]);
  return out;
}

EdgePoints DetectOrganized(const PointCloud& cloud, const EdgePointOptions& options,
                           double focal_px, const CancelToken* cancel) {
  const OrganizedScorer scorer(cloud, options, focal_px);
  // Blocks of rows, taken by the threads as they finish one (edge bands
  // gather in some rows), each with its own output, merged in row order.
  constexpr int kRowsPerBlock = 8;
  std::vector<Chunk> chunks((cloud.height + kRowsPerBlock - 1) / kRowsPerBlock);
  const int step = options.coarse_step;
  const int lattice = options.lattice_px;
  if (step <= 1) {
    internal::ParallelForChunks(
        cloud.height, kRowsPerBlock, options.num_threads, [&](int c, int begin, int end) {
          if (StopRequested(cancel)) return;
          scorer.ScoreRows(begin, end, lattice, 1, nullptr, nullptr, &chunks[c]);
        });
    return Merge(cloud, chunks);
  }
  // Coarse to fine: edge bands are several pixels wide, so a grid of one
  // pixel in step x step (of the lattice) finds every band; the pixels of
  // the hit cells and of the cells next to them that may hold a band's rim
  // are then scored at full resolution, with the real threshold.
  // The cells stay about coarse_step pixels wide on a coarser lattice: a
  // band narrower than a cell can be missed.
  const int cell_px = std::max(1, (step + lattice - 1) / lattice) * lattice;
  const int cells_w = (cloud.width + cell_px - 1) / cell_px,
            cells_h = (cloud.height + cell_px - 1) / cell_px;
  std::vector<float> cell_scores(static_cast<size_t>(cells_w) * cells_h, -1.0f);
  internal::ParallelForChunks(cells_h, 4, options.num_threads, [&](int, int begin, int end) {
    if (StopRequested(cancel)) return;
    scorer.ScoreCoarse(begin, end, cell_px, lattice, &cell_scores);
  });
  const float hit = static_cast<float>(options.threshold * options.coarse_threshold_factor);
  const float rim = static_cast<float>(options.threshold * options.coarse_skip_factor);
  std::vector<uint8_t> cells(cell_scores.size(), 0);
  for (int cv = 0; cv < cells_h; ++cv) {
    for (int cu = 0; cu < cells_w; ++cu) {
      const float own = cell_scores[cv * cells_w + cu];
      if (own >= 0.0f && own <= rim && options.coarse_skip_factor > 0.0) continue;
      bool near_hit = false;
      for (int y = std::max(0, cv - 1); y <= std::min(cells_h - 1, cv + 1) && !near_hit; ++y) {
        for (int x = std::max(0, cu - 1); x <= std::min(cells_w - 1, cu + 1); ++x) {
          if (cell_scores[y * cells_w + x] > hit) {
            near_hit = true;
            break;
          }
        }
      }
      cells[cv * cells_w + cu] = near_hit;
    }
  }
  internal::ParallelForChunks(
      cloud.height, kRowsPerBlock, options.num_threads, [&](int c, int begin, int end) {
        if (StopRequested(cancel)) return;
        scorer.ScoreRows(begin, end, lattice, cell_px, &cells, &cell_scores, &chunks[c]);
      });
  return Merge(cloud, chunks);
}

// Key of the voxel (edge `voxel` metres) holding p; 21 bits per axis, clamped
// (beyond +-2^20 voxels, far outside any sensor's range, cells merge).
uint64_t VoxelKey(const Eigen::Vector3f& p, double voxel) {
  constexpr double kHalf = 1 << 20;
  uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double cell = std::clamp(std::floor(p[axis] / voxel), -kHalf, kHalf - 1) + kHalf;
    key = (key << 21) | static_cast<uint64_t>(cell);
  }
  return key;
}

absl::StatusOr<EdgePoints> DetectUnorganized(const PointCloud& cloud,
                                             const EdgePointOptions& options,
                                             const CancelToken* cancel) {
  // Every finite point is scored, but the k-d tree holds only the first point
  // of each voxel of r_s / kKdVoxelsPerRadius: a ball of radius r_s then
  // holds at most ~(4/3) pi 8^3 = 2145 tree points however the input piles
  // up (a radius search over 200 000 identical points returned all of them,
  // for every one of them), and a surface ~200.
  constexpr double kKdVoxelsPerRadius = 8.0;
  std::vector<Eigen::Vector3f> queries;
  std::vector<int> original_index;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.xyz[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) continue;
    queries.push_back(p);
    original_index.push_back(static_cast<int>(i));
  }
  if (queries.size() > kMaxKdTreePoints) {
    return absl::InvalidArgumentError(
        absl::StrCat("unorganized cloud has ", queries.size(),
                     " finite points; the k-d tree path scores at most ", kMaxKdTreePoints,
                     " (send an organized frame or a single camera's cloud)"));
  }
  auto pcl_cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  std::unordered_set<uint64_t> taken;
  for (const Eigen::Vector3f& p : queries) {
    if (taken.insert(VoxelKey(p, options.radius_m / kKdVoxelsPerRadius)).second) {
      pcl_cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
  }
  std::vector<Chunk> chunks(options.num_threads);
  std::vector<int64_t> examined(options.num_threads, 0);
  if (pcl_cloud->empty()) return Merge(cloud, chunks);
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(pcl_cloud);
  const int n = static_cast<int>(queries.size());
  internal::ParallelForRanges(n, options.num_threads, [&](int t, int begin, int end) {
    pcl::Indices found;
    std::vector<float> dist2, dz;
    const float r2 = static_cast<float>(options.radius_m * options.radius_m);
    for (int i = begin; i < end; ++i) {
      if (i % 256 == 0 && StopRequested(cancel)) break;
      const pcl::PointXYZ q(queries[i].x(), queries[i].y(), queries[i].z());
      tree.radiusSearch(q, options.radius_m, found, dist2);
      examined[t] += static_cast<int64_t>(found.size());
      Eigen::Vector3f p = q.getVector3fMap();
      if (options.denoise && found.size() >= 3 && p.z() > 0.0f) {
        // As on organized frames: score from the neighbours' median depth,
        // moving p along its ray from the camera at the origin.
        dz.clear();
        for (const auto j : found) dz.push_back((*pcl_cloud)[j].z - p.z());
        std::nth_element(dz.begin(), dz.begin() + dz.size() / 2, dz.end());
        p *= (p.z() + dz[dz.size() / 2]) / p.z();
      }
      NeighbourSum sum;
      for (const auto j : found) {
        const Eigen::Vector3f d = (*pcl_cloud)[j].getVector3fMap() - p;
        const float d2 = d.squaredNorm();
        if (d2 <= r2) sum.Add(d, d2);
      }
      if (sum.count < options.min_neighbours) continue;
      const float score = sum.Score();
      if (score <= options.threshold) continue;
      chunks[t].indices.push_back(original_index[i]);
      chunks[t].scores.push_back(score);
    }
  });
  EdgePoints out = Merge(cloud, chunks);
  out.kdtree_points = pcl_cloud->size();
  for (int64_t e : examined) out.neighbours_examined += e;
  return out;
}

}  // namespace

absl::Status EdgePointOptions::Validate() const {
  if (!(radius_m >= 0.001 && radius_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge radius_m=", radius_m, " is outside [0.001, 0.5] m"));
  }
  if (!(threshold > 0.0 && threshold < 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge threshold=", threshold, " is outside (0, 1)"));
  }
  if (max_samples < 0 || max_samples > 4096) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge max_samples=", max_samples, " is outside [0, 4096]"));
  }
  if (min_neighbours < 1 || min_neighbours > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge min_neighbours=", min_neighbours, " is outside [1, 1000]"));
  }
  if (!(occluded_side_jump_m >= 0.0 && occluded_side_jump_m <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge occluded_side_jump_m=", occluded_side_jump_m, " is outside [0, 1] m"));
  }
  if (coarse_step < 1 || coarse_step > 16) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge coarse_step=", coarse_step, " is outside [1, 16]"));
  }
  if (!(coarse_threshold_factor > 0.0 && coarse_threshold_factor <= 1.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "edge coarse_threshold_factor=", coarse_threshold_factor, " is outside (0, 1]"));
  }
  if (lattice_px < 1 || lattice_px > 8) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge lattice_px=", lattice_px, " is outside [1, 8]"));
  }
  if (!(coarse_skip_factor >= 0.0 && coarse_skip_factor <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge coarse_skip_factor=", coarse_skip_factor, " is outside [0, 1]"));
  }
  if (num_threads < 1 || num_threads > 256) {
    return absl::InvalidArgumentError(
        absl::StrCat("num_threads=", num_threads, " is outside [1, 256]"));
  }
  return absl::OkStatus();
}

float EdgeScore(const Eigen::Vector3f& p, const std::vector<Eigen::Vector3f>& neighbours) {
  NeighbourSum sum;
  for (const Eigen::Vector3f& n : neighbours) {
    const Eigen::Vector3f d = n - p;
    sum.Add(d, d.squaredNorm());
  }
  return sum.Score();
}

absl::StatusOr<EdgePoints> DetectEdgePoints(const PointCloud& cloud,
                                            const EdgePointOptions& options, double focal_px,
                                            const CancelToken* cancel) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  if (absl::Status s = cloud.Validate(); !s.ok()) return s;
  if (cloud.organized()) {
    if (!(focal_px > 0.0 && std::isfinite(focal_px))) {
      return absl::InvalidArgumentError(absl::StrCat("focal length ", focal_px, " px is invalid"));
    }
    return DetectOrganized(cloud, options, focal_px, cancel);
  }
  return DetectUnorganized(cloud, options, cancel);
}

}  // namespace cornerpose
