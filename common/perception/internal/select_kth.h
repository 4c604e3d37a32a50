// Selection of the k-th smallest of a few dozen floats, for the edge
// score's median depth.
#pragma once

#include <algorithm>

namespace cornerpose::internal {

// The k-th smallest of a[0, n) (the value std::nth_element would put at k).
// `scratch` holds at least n floats; a and scratch are both overwritten.
// Quickselect whose partition copies into the other buffer, values below
// the pivot from the front and above it from the back, without branches:
// the values are a few dozen noisy depths, on which the compares of
// std::nth_element mispredict about every other time, and an in-place swap
// makes each step wait on the store of the step before.
inline float SelectKth(float* a, int n, int k, float* scratch) {
  float* const buffers[2] = {a, scratch};
  int into = 1;  // the buffer the next partition writes
  float* from = a;
  while (n > 1) {
    float* const to = buffers[into];
    const float x = from[0], y = from[n / 2], z = from[n - 1];
    const float pivot = std::max(std::min(x, y), std::min(std::max(x, y), z));
    // Both ends are written every step; an end keeps its value only when
    // the value belongs there (values equal to the pivot go nowhere: the
    // slots between the ends are left over).
    int below = 0, top = n - 1;
    for (int j = 0; j < n; ++j) {
      const float t = from[j];
      to[below] = t;
      to[top] = t;
      below += t < pivot;
      top -= pivot < t;
    }
    const int above = n - 1 - top;
    if (k < below) {
      from = to;
      n = below;
    } else if (k < n - above) {
      return pivot;  // the pivot is one of the values, so k lands on it
    } else {
      from = to + top + 1;
      k -= n - above;
      n = above;
    }
    into = 1 - into;
  }
  return from[0];
}

}  // namespace cornerpose::internal
