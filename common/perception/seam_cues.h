// Seam cues from a registered colour image. Two boxes that touch leave a
// line in the image where they meet (a darker gap, a change of shade) even
// where the depth shows nothing. A seam is a straight line that runs the
// whole side of a box-sized rectangle: the edges of tape, labels, print and
// barcodes inside a face are lines too, but they do not run a whole side at
// one offset, so they cannot make one.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "absl/status/status.h"
#include "common/perception/camera_model.h"

namespace cornerpose {

struct SeamCueOptions {
  // A plain line: a sample shows it when it is 0.75 of this darker than
  // both flanks (0-255 grey levels; or a step of that much, with
  // accept_steps). Also the least brightness range over a face and the band
  // around it for the colour image to say anything about it
  // (box_refinement.cc).
  double min_contrast = 10.0;
  // Whether a change of shade alone (a step) shows a seam. Off: touching
  // boxes meet in a line darker than both (the gap's shadow); the edges of
  // the tape strip along the middle of a carton's flaps are steps that run
  // its whole length, exactly where a box shifted by half its width would
  // have its side.
  bool accept_steps = false;
  // Share of the samples along the side (its ends left out) that must show
  // the line within straightness_px of one offset. Unitless, (0, 1].
  double min_coverage = 0.75;
  // A faint line is a seam too when it is darker than both its flanks by
  // at least this on average along the whole side, at one offset, and
  // min_coverage of the samples show at least half of it (grey levels; 0:
  // plain lines only). The mean is a matched filter: the grain of a
  // cardboard or brick texture (several grey levels from pixel to pixel)
  // averages out, a faint seam of 4-6 levels adds up. Stereo frames of
  // brick pallets at 2 m: 71 % of the seams between bricks are plain, 91 %
  // plain or faint.
  double min_line_contrast = 4.0;
  // ... and when it is texture_ratio times as dark as any line parallel to
  // it within texture_px beyond the search window (clear of its flanks):
  // wood grain, corrugation and print are many parallel lines, a seam is
  // one. Pixels; unitless.
  double texture_px = 7.0;
  double texture_ratio = 2.0;
  // The line is looked for this far either side of the hypothesised side
  // (registration of colour to depth is good to a few pixels). Pixels.
  double search_px = 3.0;
  // The two sides of the line are read this far from it. Pixels.
  double flank_px = 2.0;
  // Share of the side's length left out at each end (corners blur). Unitless.
  double end_margin = 0.12;
  // The samples that show the line must agree on its offset within this.
  // Pixels.
  double straightness_px = 1.5;

  absl::Status Validate() const;
};

struct SeamCue {
  double coverage = 0.0;  // share of samples showing the line at its offset
  double offset_m = 0.0;  // where the line lies, along `across` from the side
  bool seam = false;      // a plain line, or a faint one (SeamCueOptions)
  // A seam's turn against the side: its offset's change per metre along
  // the side from a to b, from where each half of the side has it (half a
  // pixel steps).
  std::optional<double> slope;
};

// Looks for a seam along the side from a to b (camera frame, metres) on a
// face; `across` is the face's in-plane unit direction across the side.
// Without a colour image, or with the side out of view, returns no seam.
SeamCue ColourSeamAlong(const DepthImage& image, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& across, const SeamCueOptions& options);

}  // namespace cornerpose
