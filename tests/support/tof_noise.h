// The time-of-flight noise model of the scene generator (see TofOptions).
// Internal to tests/support.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "tests/support/ray_caster.h"
#include "tests/support/scene_generator.h"
#include "tests/support/surface_texture.h"

namespace cornerpose::testing::internal {

// Turns the nominal render into time-of-flight depth (camera z per pixel,
// NaN where invalid). When infrared is not null it receives the active IR
// intensity image as packed grey (0x00GGGGGG).
std::vector<double> ApplyTofNoise(const RayCaster& caster, const SurfaceTexture& texture,
                                  const CameraIntrinsics& camera, const TofOptions& options,
                                  const std::vector<Hit>& nominal, std::mt19937& rng,
                                  RenderStats* stats, std::vector<uint32_t>* infrared);

}  // namespace cornerpose::testing::internal
