#include "common/process/frame_memory.h"

#include <malloc.h>

namespace cornerpose {

bool KeepFrameMemoryInProcess(int mmap_threshold_bytes, int keep_bytes, int arenas) {
  // glibc takes -1 as "never", and 0 arenas as its default.
  if (mmap_threshold_bytes <= 0 || keep_bytes <= 0 || arenas <= 0) return false;
  // mallopt returns 1 on success. Setting either turns off glibc's dynamic
  // threshold, which only rises after the first large block is freed.
  const bool mmap_ok = mallopt(M_MMAP_THRESHOLD, mmap_threshold_bytes) == 1;
  const bool trim_ok = mallopt(M_TRIM_THRESHOLD, keep_bytes) == 1;
  const bool arenas_ok = mallopt(M_ARENA_MAX, arenas) == 1;
  return mmap_ok && trim_ok && arenas_ok;
}

}  // namespace cornerpose
