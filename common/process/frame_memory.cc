#include "common/process/frame_memory.h"

#include <malloc.h>

namespace cornerpose {

bool KeepFrameMemoryInProcess(int mmap_threshold_bytes, int keep_bytes) {
  if (mmap_threshold_bytes <= 0 || keep_bytes <= 0) return false;  // glibc takes -1 as "never"
  // mallopt returns 1 on success. Setting either turns off glibc's dynamic
  // threshold, which only rises after the first large block is freed.
  const bool mmap_ok = mallopt(M_MMAP_THRESHOLD, mmap_threshold_bytes) == 1;
  const bool trim_ok = mallopt(M_TRIM_THRESHOLD, keep_bytes) == 1;
  return mmap_ok && trim_ok;
}

}  // namespace cornerpose
