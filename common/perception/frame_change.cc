#include "common/perception/frame_change.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/perception/internal/summed_area.h"
#include "common/validation/range_check.h"

namespace cornerpose {

absl::Status FrameChangeOptions::Validate() const {
  for (absl::Status s :
       {CheckRange("frame_change.block_px", block_px, 2, 64),
        CheckRange("frame_change.min_depth_change_m", min_depth_change_m, 0.0, 1.0),
        CheckRange("frame_change.depth_change_per_m2", depth_change_per_m2, 0.0, 1.0),
        CheckRange("frame_change.window_blocks", window_blocks, 0, kMaxWindowBlocks),
        CheckRange("frame_change.box_side_m", box_side_m, 0.0, 10.0),
        CheckRange("frame_change.focal_px", focal_px, 0.0, 1e5),
        CheckRange("frame_change.max_valid_share_change", max_valid_share_change, 0.0, 1.0),
        CheckRange("frame_change.min_valid_share", min_valid_share, 0.0, 1.0),
        CheckRange("frame_change.max_changed_blocks", max_changed_blocks, 0, 1000000)}) {
    if (!s.ok()) return s;
  }
  if (min_depth_change_m <= 0.0 && depth_change_per_m2 <= 0.0) {
    return absl::InvalidArgumentError(
        "frame_change.min_depth_change_m and depth_change_per_m2 are both 0: noise alone would "
        "change every frame");
  }
  return absl::OkStatus();
}

namespace {

// Depths beyond this are no return (and keep the sums finite). Metres.
constexpr float kFarthest = 1000.0f;

// One row of blocks: per block, the count and sum of its valid depths.
struct BlockRow {
  std::vector<int> count;
  std::vector<double> sum;
  explicit BlockRow(int blocks) : count(blocks), sum(blocks) {}
  double Mean(int i) const { return sum[i] / count[i]; }
};

void SumBlockRow(const PointCloud& cloud, int by, int block, BlockRow* row) {
  const int blocks_x = static_cast<int>(row->sum.size());
  std::fill(row->count.begin(), row->count.end(), 0);
  std::fill(row->sum.begin(), row->sum.end(), 0.0);
  const int y_end = std::min(cloud.height, (by + 1) * block);
  for (int y = by * block; y < y_end; ++y) {
    const Eigen::Vector3f* p = cloud.xyz.data() + static_cast<size_t>(y) * cloud.width;
    for (int bx = 0; bx < blocks_x; ++bx) {
      const int x_end = std::min(cloud.width, (bx + 1) * block);
      double s = 0.0;
      int n = 0;
      for (int x = bx * block; x < x_end; ++x) {
        const float z = p[x].z();
        if (z > 0.0f && z < kFarthest) {  // false for NaN
          s += z;
          ++n;
        }
      }
      row->count[bx] += n;
      row->sum[bx] += s;
    }
  }
}

}  // namespace

absl::StatusOr<FrameChange> CompareFrames(const PointCloud& before, const PointCloud& after,
                                          const FrameChangeOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  FrameChange change;
  if (!before.organized() || !after.organized() || before.width != after.width ||
      before.height != after.height || before.size() != after.size() ||
      before.size() != static_cast<size_t>(before.width) * before.height) {
    return change;
  }
  // Per block: whether it is compared, its depth change where both frames
  // have depth there, and the change in the share of pixels with a return.
  const int block = options.block_px;
  const int bw = (before.width + block - 1) / block;
  const int bh = (before.height + block - 1) / block;
  const size_t n = static_cast<size_t>(bw) * bh;
  std::vector<double> compared(n, 0.0), with_depth(n, 0.0), dz(n, 0.0), z(n, 0.0), dshare(n, 0.0);
  BlockRow a(bw), b(bw);
  for (int by = 0; by < bh; ++by) {
    SumBlockRow(before, by, block, &a);
    SumBlockRow(after, by, block, &b);
    const int rows = std::min(block, before.height - by * block);
    for (int bx = 0; bx < bw; ++bx) {
      const size_t i = static_cast<size_t>(by) * bw + bx;
      const int cols = std::min(block, before.width - bx * block);
      const double pixels = static_cast<double>(rows) * cols;
      const double share_a = a.count[bx] / pixels, share_b = b.count[bx] / pixels;
      if (share_a < options.min_valid_share && share_b < options.min_valid_share) continue;
      compared[i] = 1.0;
      dshare[i] = share_b - share_a;
      if (share_a >= options.min_valid_share && share_b >= options.min_valid_share) {
        with_depth[i] = 1.0;
        dz[i] = b.Mean(bx) - a.Mean(bx);
        z[i] = std::max(a.Mean(bx), b.Mean(bx));
      }
    }
  }
  // Each block is judged by the mean change over a window around it as big
  // as the box's smallest side there: the noise (correlated over a few
  // pixels) averages out, a box taken or put down moves the whole window.
  using Sums = internal::SummedArea<double>;
  const Sums sum_compared(compared, bw, bh), sum_with_depth(with_depth, bw, bh), sum_dz(dz, bw, bh),
      sum_z(z, bw, bh), sum_dshare(dshare, bw, bh);
  for (int by = 0; by < bh; ++by) {
    for (int bx = 0; bx < bw; ++bx) {
      const size_t i = static_cast<size_t>(by) * bw + bx;
      if (compared[i] == 0.0) continue;
      ++change.compared_blocks;
      int r = options.window_blocks;
      if (options.box_side_m > 0.0 && options.focal_px > 0.0 && z[i] > 0.0) {
        const double side_px = options.focal_px * options.box_side_m / z[i];
        r = std::clamp(static_cast<int>(0.5 * side_px / block), 1, kMaxWindowBlocks);
      }
      // The window [bx - r, bx + r] x [by - r, by + r] (the sums clip it).
      const auto window = [&](const Sums& sums) {
        return sums.Sum(bx - r, by - r, bx + r + 1, by + r + 1);
      };
      bool moved =
          std::abs(window(sum_dshare) / window(sum_compared)) > options.max_valid_share_change;
      const double nd = window(sum_with_depth);
      if (!moved && nd > 0.0) {
        const double zm = window(sum_z) / nd;
        moved = std::abs(window(sum_dz) / nd) >
                options.min_depth_change_m + options.depth_change_per_m2 * zm * zm;
      }
      change.changed_blocks += moved;
    }
  }
  change.same_scene = change.changed_blocks <= options.max_changed_blocks;
  return change;
}

}  // namespace cornerpose
