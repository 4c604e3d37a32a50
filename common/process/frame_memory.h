// How the process's allocator treats the large buffers of a detection.
#pragma once

namespace cornerpose {

// A frame's buffers (a VGA cloud is 3.7 MB, its depth image 1.2 MB) are
// above glibc's default mmap threshold (128 KiB at start), so each is mapped
// fresh and unmapped when freed: the next one faults in every page again, at
// ~10 us a page on a VM. This keeps blocks up to `mmap_threshold_bytes` in
// the heap and freed heap memory up to `keep_bytes` in the process, so a
// frame reuses what the last one (or the file reader) touched. And it
// bounds the allocator's arenas to `arenas`: each arena keeps its own freed
// memory, and glibc makes up to 8 a core, so a server whose threads (a
// stream's, a pool worker's, gRPC's) each held a frame for a while would
// keep a frame's worth in every one (a 7-minute soak: 66 -> 437 MiB
// resident with glibc's default, 214-255 MiB throughout with 2). Call once,
// first thing in main(), before other threads start. Returns false,
// changing nothing, when a value is not positive, and false when the
// allocator refused.
bool KeepFrameMemoryInProcess(int mmap_threshold_bytes = 256 << 20, int keep_bytes = 256 << 20,
                              int arenas = 2);

}  // namespace cornerpose
