// How the process's allocator treats the large buffers of a detection.
#pragma once

namespace cornerpose {

// A frame's buffers (a VGA cloud is 3.7 MB, its depth image 1.2 MB) are
// above glibc's default mmap threshold (128 KiB at start), so each is mapped
// fresh and unmapped when freed: the next one faults in every page again, at
// ~10 us a page on a VM. This keeps blocks up to `mmap_threshold_bytes` in
// the heap and freed heap memory up to `keep_bytes` in the process, so a
// frame reuses what the last one (or the file reader) touched. Call once,
// first thing in main(). Returns false, changing nothing, when a size is
// not positive, and false when the allocator refused.
bool KeepFrameMemoryInProcess(int mmap_threshold_bytes = 256 << 20, int keep_bytes = 256 << 20);

}  // namespace cornerpose
