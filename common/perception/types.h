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

// The known size of the boxes to find, metres: l along the box x axis,
// b along y, h along z.
struct BoxDims {
  double l = 0.0;
  double b = 0.0;
  double h = 0.0;

  double operator[](int axis) const { return axis == 0 ? l : axis == 1 ? b : h; }
  Eigen::Vector3d vec() const { return {l, b, h}; }
  // INVALID_ARGUMENT when a side is not finite, <= 0, or above 10 m.
  absl::Status Validate() const;
};

// One of the six faces of a box: +x is the face at x = +l/2, and so on.
enum class BoxFace : uint8_t { kPlusX = 0, kMinusX, kPlusY, kMinusY, kPlusZ, kMinusZ };
const char* BoxFaceName(BoxFace face);  // "+x", "-x", ...
// Outward unit normal of a face in the box frame.
Eigen::Vector3d BoxFaceNormal(BoxFace face);

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

// A box found in the cloud.
struct DetectedBox {
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  // Confidence in [0, 1]: the share of the box's expected visible surface
  // that the cloud confirms, lowered by contradicting evidence.
  double score = 0.0;
  BoxFace grasp_face = BoxFace::kPlusZ;  // the face that looks at the camera
  Eigen::Vector3d grasp_centre_camera = Eigen::Vector3d::Zero();  // its centre, m
  Eigen::Vector3d grasp_normal_camera = Eigen::Vector3d::Zero();  // its outward normal
  std::vector<int> segments;  // edge segments that support the box
  int num_corners = 0;        // corners used for its pose
  // The grasp face's size as measured between two ends (free sides or
  // seams) along its two in-plane box axes, (n+1) % 3 and (n+2) % 3 for the
  // face's normal axis n; 0 where a side was not measured. Metres.
  std::array<double, 2> measured_extent_m{0.0, 0.0};
  bool from_face = false;  // proposed by a planar patch (else by corners or a neighbour)
};

// A hypothesis the detector did not return, and why: what an integrator
// reads to tune a cell ("face tiles two ways", "side runs on flat", ...).
struct DeclinedCandidate {
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  // Its render-and-compare support before refinement, in [0, 1]; 0 when it
  // was declined before any (an ambiguous tiling).
  double score = 0.0;
  std::string reason;
};

// Wall-clock time of each stage, milliseconds.
struct StageTimings {
  double preprocess_ms = 0.0;
  double edge_points_ms = 0.0;
  double edge_segments_ms = 0.0;
  double clubbing_ms = 0.0;
  double poses_ms = 0.0;
  double total_ms = 0.0;
  // Planar patches and their tilings (last, so the fields above keep their
  // order for aggregate initialisation).
  double faces_ms = 0.0;
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
  // The strongest hypotheses not returned, strongest first, each with a
  // reason (at most DetectorOptions::max_declined).
  std::vector<DeclinedCandidate> declined;
  StageTimings timings;
  HypothesisStats hypotheses;
};

}  // namespace cornerpose
