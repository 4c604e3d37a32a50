// Sums over axis-aligned rectangles of a grid in O(1): a summed-area table
// (the anchored faces' cell counts, the frame comparison's block windows).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace cornerpose::internal {

// T is the type sums are kept in (int for counts, double for depths).
template <typename T>
class SummedArea {
 public:
  // `values`: w x h, row-major.
  template <typename V>
  SummedArea(const std::vector<V>& values, int w, int h)
      : w_(w), h_(h), sum_(static_cast<size_t>(w + 1) * (h + 1), T{}) {
    for (int j = 0; j < h; ++j) {
      T row{};
      for (int i = 0; i < w; ++i) {
        row += values[static_cast<size_t>(j) * w + i];
        sum_[At(i + 1, j + 1)] = sum_[At(i + 1, j)] + row;
      }
    }
  }
  // Over [i0, i1) x [j0, j1), clipped to the grid; T{} when that is empty.
  T Sum(int i0, int j0, int i1, int j1) const {
    i0 = std::clamp(i0, 0, w_), i1 = std::clamp(i1, 0, w_);
    j0 = std::clamp(j0, 0, h_), j1 = std::clamp(j1, 0, h_);
    if (i1 <= i0 || j1 <= j0) return T{};
    return sum_[At(i1, j1)] - sum_[At(i0, j1)] - sum_[At(i1, j0)] + sum_[At(i0, j0)];
  }

 private:
  size_t At(int i, int j) const { return static_cast<size_t>(j) * (w_ + 1) + i; }
  int w_, h_;
  std::vector<T> sum_;
};

}  // namespace cornerpose::internal
