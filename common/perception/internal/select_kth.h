// Selection of the k-th smallest of a few dozen floats, for the edge
// score's median depth.
#pragma once

#include <algorithm>

namespace cornerpose::internal {

// The k-th smallest of a[0, n) (the value std::nth_element would put at k),
// reordering a. Quickselect with a branch-free Lomuto partition: the values
// are a few dozen noisy depths, on which the compares of std::nth_element
// mispredict about every other time.
inline float SelectKth(float* a, int n, int k) {
  int lo = 0, hi = n - 1;
  while (hi > lo) {
    const float x = a[lo], y = a[(lo + hi) / 2], z = a[hi];
    const float pivot = std::max(std::min(x, y), std::min(std::max(x, y), z));
    // a[lo, i) < pivot <= a[i, hi].
    int i = lo;
    for (int j = lo; j <= hi; ++j) {
      const float t = a[j];
      a[j] = a[i];
      a[i] = t;
      i += t < pivot;
    }
    if (k < i) {
      hi = i - 1;
      continue;
    }
    // a[i, e) == pivot < a[e, hi] (the pivot is one of the values).
    int e = i;
    for (int j = i; j <= hi; ++j) {
      const float t = a[j];
      a[j] = a[e];
      a[e] = t;
      e += !(pivot < t);
    }
    if (k < e) return pivot;
    lo = e;
  }
  return a[k];
}

}  // namespace cornerpose::internal
