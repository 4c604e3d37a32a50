// What the depth image says about a box hypothesis: the box is rendered into
// the camera by ray casting and each pixel it covers is compared with the
// measured depth. A real box is confirmed on its visible faces; a wrong one
// is contradicted by pixels seen *through* it (points inside its volume or
// behind it) and by faces the camera should see but that return nothing.
#pragma once

#include "absl/status/status.h"
#include "common/perception/camera_model.h"
#include "common/perception/types.h"

namespace cornerpose {

struct EvidenceOptions {
  // A measured depth agrees with the rendered one within
  // base + per_m2 * z^2 (the Kinect's error grows with z^2). Metres, 1/metre.
  double depth_tolerance_base_m = 0.008;
  double depth_tolerance_per_m2 = 0.004;
  // At most this many pixels are tested per box (a regular subsample). Count.
  int max_samples = 3000;
  // The first look at an unrefined hypothesis (HypothesisJudge: is it worth
  // refining?) tests at most this many: its thresholds are wide, and half
  // of all hypotheses end there. [10, 1e7], and never more than max_samples.
  // 400 (1000 before session 35): a sixth of the pose stage was this look,
  // mostly at neighbours proposed into free space; on the 94 evaluation
  // sets two boxes more, no wrong one, the real frames the same. Count.
  int gate_max_samples = 400;
  // Pixels within this distance of the box's projected outline that do not
  // agree (seen through or no return) are counted as `border`, not against
  // the box: stereo edge fattening, flying and mixed pixels between a box
  // and what lies behind it, and a real box a little off its nominal size
  // all live there. Metres on the box, turned into pixels at the box's depth
  // (fx / z), at least one pixel. DetectBoxes sets it to half the edge
  // radius r_s (the scale at which the edge detector resolves an outline).
  // [0, 0.1]; 0 counts every pixel.
  double outline_margin_m = 0.01;
  // On the faces other than the one the box shows most (its sides, seen
  // obliquely and meeting the floor or a neighbour in concave creases), a
  // pixel up to this much further behind than the tolerance is neither
  // agreement nor see-through but `border`: a time-of-flight camera's
  // multipath biases the depth near concave creases by up to a few
  // centimetres away from the camera (a real isolated carton's sides read
  // 6-8 % "seen through" without it). A box placed where there is free
  // space shows what lies behind much further back, or on its main face.
  // Metres, [0, 0.1]; 0 treats every face alike.
  double side_face_allowance_m = 0.025;

  absl::Status Validate() const;
};

struct FaceEvidence {
  int expected = 0;     // pixels where the rendered box shows this face
  int agree = 0;        // ... and the measured depth matches it
  int occluded = 0;     // ... measured in front of it (something on top)
  int see_through = 0;  // ... measured behind it (free space where the box would be)
  int missing = 0;      // ... no return
  // Not in `expected`: pixels near the outline that are seen through or
  // have no return (EvidenceOptions::outline_margin_m).
  int border = 0;
  int visible() const { return expected - occluded; }
};

struct BoxEvidence {
  std::array<FaceEvidence, 6> faces;  // by BoxFace
  FaceEvidence total;
  BoxFace grasp_face = BoxFace::kPlusZ;  // the face with the most rendered pixels
  bool in_front_of_camera = true;

  // Share of the box's unoccluded pixels that the measurement confirms.
  double support() const {
    return total.visible() > 0 ? static_cast<double>(total.agree) / total.visible() : 0.0;
  }
  double see_through_fraction() const {
    return total.expected > 0 ? static_cast<double>(total.see_through) / total.expected : 1.0;
  }
  double visible_fraction() const {
    return total.expected > 0 ? static_cast<double>(total.visible()) / total.expected : 0.0;
  }
  const FaceEvidence& grasp() const { return faces[static_cast<int>(grasp_face)]; }
};

BoxEvidence MeasureBox(const DepthImage& depth, const Eigen::Isometry3d& camera_T_box,
                       const BoxDims& dims, const EvidenceOptions& options);

}  // namespace cornerpose
