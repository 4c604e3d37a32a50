// The plain box types every part shares: the detector (common/perception),
// the wire library (common/wire) and the robot-cell daemon. Eigen and absl
// only: no PCL, no protobuf, so the daemon can use them without the
// perception core.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "absl/status/status.h"

namespace cornerpose {

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
};

}  // namespace cornerpose
