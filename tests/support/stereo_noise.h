// The active-stereo noise model of the scene generator (see StereoOptions).
// Internal to tests/support.
#pragma once

#include <random>
#include <vector>

#include "tests/support/ray_caster.h"
#include "tests/support/scene_generator.h"
#include "tests/support/surface_texture.h"

namespace cornerpose::testing::internal {

// Turns the nominal render into stereo depth (camera z per pixel, NaN where
// invalid). `caster` must place its projector at the right imager
// (projector_offset_m = options.baseline_m).
std::vector<double> ApplyStereoNoise(const RayCaster& caster, const SurfaceTexture& texture,
                                     const CameraIntrinsics& camera, const StereoOptions& options,
                                     const std::vector<Hit>& nominal, std::mt19937& rng,
                                     RenderStats* stats);

// 1D grey-scale min / max filters of half width r along rows (or columns).
void MinFilter1d(std::vector<double>* values, int width, int height, int r, bool along_x);
void MaxFilter1d(std::vector<double>* values, int width, int height, int r, bool along_x);

}  // namespace cornerpose::testing::internal
