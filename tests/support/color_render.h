// The registered colour image: the scene's albedo (surface_texture.h) lit by
// a soft light from above with cast shadows, supersampled where surfaces
// meet, then a colour sensor's vignetting, gamma and noise. Internal to
// tests/support.
#pragma once

#include <cstdint>
#include <vector>

#include "tests/support/ray_caster.h"
#include "tests/support/scene_generator.h"
#include "tests/support/surface_texture.h"

namespace cornerpose::testing::internal {

// One packed 0x00RRGGBB per pixel, row-major. `nominal` is the ray cast
// through the pixel centres; seed drives the light and the sensor noise.
std::vector<uint32_t> RenderColor(const Scene& scene, const RayCaster& caster,
                                  const SurfaceTexture& texture, const std::vector<Hit>& nominal,
                                  const ColorOptions& options, uint32_t seed);

// Packs linear intensities in [0, 1] into 8-bit sRGB-like grey or colour.
uint32_t PackColor(const Eigen::Vector3d& linear);

}  // namespace cornerpose::testing::internal
