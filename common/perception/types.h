// Plain data types shared by every stage of the detector. No PCL, no gRPC:
// this header is included everywhere, so it stays light.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "common/box/box_types.h"  // BoxDims, BoxFace, DetectedBox: shared beyond the core

namespace cornerpose {

// A point cloud in the camera frame (x right, y down, z forward), metres.
// Organized when height > 1: point (u, v) is xyz[v * width + u], and a pixel
// without a return holds NaN in all three coordinates. Unorganized clouds have
// height == 1 and may still contain NaN points (they are ignored).
struct PointCloud {
  int width = 0;
  int height = 0;
  std::vector<Eigen::Vector3f> xyz;
  // Optional colour (or infrared intensity as grey) registered to the points:
  // rgb[i] is the colour of xyz[i], packed 0x00RRGGBB. Empty when the frame
  // has none; the detector then works on depth alone.
  std::vector<uint32_t> rgb;

  bool organized() const { return height > 1; }
  size_t size() const { return xyz.size(); }
  bool empty() const { return xyz.empty(); }
  // The detector marks every point it cannot use (a NaN, an infinity or an
  // absurd coordinate in any axis) with a NaN z, so this test suffices
  // inside it (see SanitizeCloud in detector.cc).
  static bool IsValid(const Eigen::Vector3f& p) { return std::isfinite(p.z()); }

  bool has_color() const { return !rgb.empty(); }
  // OK when width * height == xyz.size() and both are positive, or all are
  // zero (an empty cloud), and rgb is empty or as long as xyz.
  absl::Status Validate() const;
};

// Pinhole intrinsics of a depth camera, in pixels.
struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;

  absl::Status Validate() const;
};

// An edge segment found in the edge points: two extremities and its support.
struct EdgeSegment {
  Eigen::Vector3f end1 = Eigen::Vector3f::Zero();        // camera frame, m
  Eigen::Vector3f end2 = Eigen::Vector3f::Zero();        // camera frame, m
  Eigen::Vector3f point = Eigen::Vector3f::Zero();       // a point on the fitted line, m
  Eigen::Vector3f direction = Eigen::Vector3f::UnitX();  // unit, end1 -> end2
  int num_points = 0;                                    // edge points assigned to it

  float length() const { return (end2 - end1).norm(); }
};

// Where two perpendicular edge segments meet.
struct Corner {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  // camera frame, m
  int segment_a = -1;                                  // index into the segment list
  int segment_b = -1;
  bool a_at_end1 = true;  // which extremity of segment_a meets
  bool b_at_end1 = true;
};

// Wall-clock time of each stage, milliseconds.
struct StageTimings {
  double preprocess_ms = 0.0;
  double edge_points_ms = 0.0;
  double edge_segments_ms = 0.0;
  double clubbing_ms = 0.0;
  double poses_ms = 0.0;
  double total_ms = 0.0;
};

// How much work the pose stage did: hypotheses proposed (corners and
// neighbours), refined after the first render-and-compare, and accepted.
struct HypothesisStats {
  int proposed = 0;
  int refined = 0;
  int accepted = 0;
};

// Everything the detector found in one frame.
struct Detection {
  std::vector<Eigen::Vector3f> edge_points;  // camera frame, m
  std::vector<EdgeSegment> segments;
  std::vector<Corner> corners;
  std::vector<DetectedBox> boxes;  // best score first
  StageTimings timings;
  HypothesisStats hypotheses;
};

}  // namespace cornerpose
