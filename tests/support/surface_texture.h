// What the scene's surfaces look like: the albedo of every point of a box,
// support part or the floor, drawn once per scene from its noise seed.
// Internal to tests/support; used by the colour rendering and by the sensor
// models whose noise depends on the surface (dark print loses stereo texture,
// a dark surface returns less time-of-flight light).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "tests/support/ray_caster.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing::internal {

// Smooth value noise in [0, 1]: a hashed lattice, smoothstep-interpolated.
double ValueNoise(double x, double y, uint32_t seed);

class SurfaceTexture {
 public:
  SurfaceTexture(const Scene& scene, const RayCaster& caster);

  // Linear RGB albedo, each channel in [0, 1], of the surface `hit` at
  // camera-frame point p (on that surface). Black where nothing was hit.
  Eigen::Vector3d Albedo(const Hit& hit, const Eigen::Vector3d& p) const;
  // Luminance of the albedo (Rec. 709), e.g. the surface's near-infrared reflectance.
  double Luma(const Hit& hit, const Eigen::Vector3d& p) const;

 private:
  // A printed rectangle on one face, in that face's 2D coordinates.
  struct Print {
    int face = 0;
    double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
    bool label = true;  // white label with barcode and text; else a coloured logo
    bool round = false;
    Eigen::Vector3d ink{0, 0, 0};
    uint32_t seed = 0;
  };
  struct BoxLook {
    bool brick = false;
    Eigen::Vector3d base{0.5, 0.3, 0.13};
    double face_shade[6] = {1, 1, 1, 1, 1, 1};
    int tape = 0;  // 0 none, 1 brown, 2 clear, 3 white
    double tape_half_width = 0.024, tape_offset = 0.0, tape_flap = 0.06;
    std::vector<Print> prints;
    uint32_t seed = 0;
  };
  struct PartLook {
    Eigen::Vector3d base{0.5, 0.4, 0.25};
    int grain_axis = 0;  // -1 for no grain (metal, laminate)
    uint32_t seed = 0;
  };

  Eigen::Vector3d BoxAlbedo(int i, int face, const Eigen::Vector3d& q) const;
  Eigen::Vector3d PartAlbedo(int part, const Eigen::Vector3d& q) const;
  Eigen::Vector3d FloorAlbedo(const Eigen::Vector3d& world) const;

  const RayCaster& caster_;
  Eigen::Isometry3d world_T_camera_;
  std::vector<BoxLook> boxes_;
  std::vector<PartLook> parts_;
  Eigen::Vector3d floor_base_;
  uint32_t floor_seed_ = 0;
};

}  // namespace cornerpose::testing::internal
