// What became of one pixel of a simulated depth sensor, and the last step
// every sensor model (kinect_noise, stereo_noise, tof_noise) shares.
#pragma once

#include <cstdint>
#include <vector>

#include "tests/support/scene_generator.h"

namespace cornerpose::testing::internal {

// Per pixel, as a uint8_t in the models' status images.
enum PixelStatus : uint8_t {
  kValid,
  kNoReturn,  // nothing hit, or out of the working range
  kShadow,    // occluded from the projector or the second camera
  kGrazing,   // too oblique, or too weak a return (time of flight)
  kDropout,   // random holes, speckle, blobs
};

// Valid pixels outside [min_range_m, max_range_m] get no return; every pixel
// is counted in `stats` by its status; the others become NaN and valid ones
// are rounded to output_step_m when it is > 0.
void FinishPixels(std::vector<uint8_t>& status, double min_range_m, double max_range_m,
                  double output_step_m, std::vector<double>& depth, RenderStats* stats);

}  // namespace cornerpose::testing::internal
