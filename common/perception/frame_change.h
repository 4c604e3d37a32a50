// Whether a depth frame shows the same scene as an earlier one: the test a
// stream uses to carry the earlier frame's boxes instead of detecting again
// (a cell's camera sees the same pallet for seconds between picks, each
// frame with new sensor noise).
//
// The frames are compared in blocks of pixels: each block's mean depth and
// how many of its pixels have a return, and each block is judged by the mean
// change over a window around it as big as the box's smallest side. The
// sensors' noise is correlated over a few pixels and averages out over such
// a window; a box taken or put down moves the whole window by a box height.
// The threshold grows with depth as the sensors' error does (z²).
//
// What it does not see: a box moved by a few centimetres inside a layer of
// touching boxes (only its outline changes, and that by less than the
// noise along every outline): its carried pose stays off by that much until
// anything else in view changes. Colour is not compared.
#pragma once

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/perception/types.h"

namespace cornerpose {

inline constexpr int kMaxWindowBlocks = 8;

struct FrameChangeOptions {
  // Side of the compared blocks, pixels (8: 4800 blocks a VGA frame).
  int block_px = 8;
  // Each block is judged by the mean change over the blocks around it, a
  // window as big as the box's smallest side at that block's depth
  // (box_side_m, metres, and focal_px, the camera's fx), or of
  // 2 window_blocks + 1 blocks a side when either is 0; at most
  // 2 kMaxWindowBlocks + 1.
  double box_side_m = 0.0;
  double focal_px = 0.0;
  int window_blocks = 1;
  // A window has changed when its mean depth moved by more than
  // min_depth_change_m + depth_change_per_m2 z² (z its mean depth, metres),
  // or the share of its pixels with a return by more than
  // max_valid_share_change (a box taken leaves a hole or a shadow).
  // With the defaults 2.2 cm at 1.5 m, 4.6 cm at 2.5 m: a carton or brick
  // taken changes dozens of windows on every sensor model (the layer below
  // lies a box height deeper), noise none or a few (frame_change_test).
  double min_depth_change_m = 0.008;
  double depth_change_per_m2 = 0.006;
  double max_valid_share_change = 0.3;
  // Blocks with fewer valid pixels than this share in a frame have no depth
  // in it; in neither, they are not compared. Unitless.
  double min_valid_share = 0.25;
  // The scene is the same when at most this many blocks' windows changed
  // (noise now and then; a box taken changes twenty or more). Blocks.
  int max_changed_blocks = 8;

  // Names the field out of range.
  absl::Status Validate() const;
};

struct FrameChange {
  int compared_blocks = 0;  // blocks with enough valid pixels in either frame
  int changed_blocks = 0;
  // The same scene: same size, both organized, at most max_changed_blocks
  // changed. False for unorganized clouds (they have no pixels to compare).
  bool same_scene = false;
};

// Compares `after` with `before`. INVALID_ARGUMENT for options out of range;
// clouds of different sizes or unorganized clouds are not the same scene.
absl::StatusOr<FrameChange> CompareFrames(const PointCloud& before, const PointCloud& after,
                                          const FrameChangeOptions& options = {});

}  // namespace cornerpose
