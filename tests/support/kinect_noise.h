// The Kinect v1 noise model of the scene generator (see NoiseOptions).
// Internal to tests/support.
#pragma once

#include <random>
#include <vector>

#include "tests/support/ray_caster.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing::internal {

// A zero-mean, unit-variance Gaussian random field: white noise blurred with
// a Gaussian of sigma_px, then renormalized.
std::vector<double> SmoothGaussianField(int width, int height, double sigma_px, std::mt19937& rng);

// Turns the nominal render (one Hit per pixel) into noisy depth: the camera z
// of each pixel, NaN where invalid.
std::vector<double> ApplyKinectNoise(const RayCaster& caster, const CameraIntrinsics& camera,
                                     const NoiseOptions& noise, const std::vector<Hit>& nominal,
                                     std::mt19937& rng, RenderStats* stats);

}  // namespace cornerpose::testing::internal
