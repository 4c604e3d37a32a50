// The whole detector: edge points -> edge segments -> corners -> box poses,
// each pose checked against the depth image before it is returned. A wrong
// pose is worse than a missed box (a robot acts on it), so every hypothesis
// must be confirmed by its grasp face and not contradicted anywhere.
#pragma once

#include <optional>

#include "absl/status/statusor.h"
#include "common/perception/box_evidence.h"
#include "common/perception/box_pose.h"
#include "common/perception/box_refinement.h"
#include "common/perception/clubbing.h"
#include "common/perception/edge_points.h"
#include "common/perception/edge_segments.h"
#include "common/perception/types.h"

namespace cornerpose {

// Frames above this many points are refused: by the detector
// (DetectorOptions::max_points) and by the wire library before it unpacks
// one. Count.
inline constexpr int kMaxPoints = 20'000'000;

struct AcceptanceOptions {
  // Share of the box's unoccluded rendered pixels the depth confirms. Unitless.
  double min_support = 0.6;
  // Share of the grasp face's unoccluded pixels the depth confirms. Unitless.
  double min_grasp_support = 0.8;
  // Share of the grasp face that may be hidden by something in front. Unitless.
  double max_grasp_occluded = 0.25;
  // Largest share of the box's rendered pixels hidden by something in front
  // of it. Unitless.
  double max_occluded = 0.3;
  // Largest share of rendered pixels seen through the box (free space or
  // points inside its volume where the box would be). Unitless.
  double max_see_through = 0.05;
  // Grasp face pixels needed (at the sampling the evidence uses). Count.
  int min_grasp_pixels = 60;
  // A face measured between two free sides must match its known size within
  // this. Metres.
  double extent_tolerance_m = 0.025;
  // Largest angle between the grasp face's normal and the line of sight to
  // its centre. Degrees.
  double max_grasp_view_angle_deg = 60.0;
  // The grasp face must project this far inside the image. Pixels.
  double border_margin_px = 3.0;
  // Two accepted boxes may not overlap by more than this (each is shrunk by
  // it before the overlap test). Metres.
  double overlap_margin_m = 0.015;

  absl::Status Validate() const;
};

struct DetectorOptions {
  BoxDims box;  // required: the known size of the boxes, metres
  EdgePointOptions edge_points;
  EdgeSegmentOptions segments;
  ClubbingOptions clubbing;
  PoseOptions pose;
  RefinementOptions refinement;
  EvidenceOptions evidence;
  AcceptanceOptions acceptance;
  // The camera of an unorganized cloud, used to render hypotheses; organized
  // clouds carry their own (recovered from the points). Default: Kinect VGA.
  std::optional<CameraIntrinsics> camera;
  // Each confirmed box proposes the boxes that would touch it side by side
  // (pallet layers, where seams leave few edges), neighbour_gap_m apart.
  bool propagate_to_neighbours = true;
  double neighbour_gap_m = 0.002;
  // Unorganized clouds are projected through `camera` onto its pixel grid
  // (the nearest point per pixel) and processed like a frame. Right for a
  // cloud from one depth camera, in its frame; for merged or foreign clouds
  // set it false to score edges over a k-d tree as the paper does (also
  // done when fewer than half the points project into the image).
  bool project_unorganized = true;
  // Worker threads (edge points). Count.
  int num_threads = 2;
  // Frames above this many points are refused. Count.
  int max_points = kMaxPoints;

  absl::Status Validate() const;
};

// Sets the edge radius r_s and the gap at which a segment ends, which
// Algorithm 1 ties to it: every front end sets r_s through this.
void SetEdgeRadius(double radius_m, DetectorOptions* options);

// The camera of a frame whose source knows it (a depth image, a device)
// replaces the one in *options (a request's intrinsics, the default); a
// frame without one leaves *options unchanged.
void UseFrameCamera(const std::optional<CameraIntrinsics>& frame_camera, DetectorOptions* options);

// Runs the detector on one cloud. Empty, all-NaN and box-free clouds give an
// empty Detection; malformed clouds and bad options give INVALID_ARGUMENT.
absl::StatusOr<Detection> DetectBoxes(const PointCloud& cloud, const DetectorOptions& options);

}  // namespace cornerpose
