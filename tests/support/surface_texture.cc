#include "tests/support/surface_texture.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace cornerpose::testing::internal {
namespace {

uint32_t Mix(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

uint32_t Hash(uint32_t a, uint32_t b, uint32_t c) {
  return Mix(a * 0x9E3779B1u ^ Mix(b * 0x85EBCA77u ^ Mix(c + 0x27d4eb2fu)));
}

double Hash01(uint32_t a, uint32_t b, uint32_t c) { return Hash(a, b, c) * (1.0 / 4294967296.0); }

double Uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// The two in-plane axes of a face (2 axis + sign) of a cuboid.
void FaceAxes(int face, int* a1, int* a2) {
  const int axis = face / 2;
  *a1 = axis == 2 ? 0 : (axis + 1) % 3;
  *a2 = axis == 2 ? 1 : (axis + 2) % 3;
}

bool IsBrick(const BoxDims& d) { return d.h <= 0.07 && d.l <= 0.25; }

}  // namespace

double ValueNoise(double x, double y, uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const auto ix = static_cast<uint32_t>(static_cast<int64_t>(fx));
  const auto iy = static_cast<uint32_t>(static_cast<int64_t>(fy));
  const double a = Hash01(ix, iy, seed), b = Hash01(ix + 1, iy, seed);
  const double c = Hash01(ix, iy + 1, seed), d = Hash01(ix + 1, iy + 1, seed);
  return (a + (b - a) * sx) * (1 - sy) + (c + (d - c) * sx) * sy;
}

SurfaceTexture::SurfaceTexture(const Scene& scene, const RayCaster& caster)
    : caster_(caster), world_T_camera_(scene.world_T_camera) {
  // Its own stream: the look never disturbs the depth noise.
  std::mt19937 rng(Hash(scene.LookSeed(), 0xC010u, 7u));
  for (size_t i = 0; i < scene.boxes.size(); ++i) {
    const BoxDims& dims = scene.boxes[i].dims;
    BoxLook look;
    look.seed = Hash(scene.LookSeed(), static_cast<uint32_t>(i), 11u);
    look.brick = IsBrick(dims);
    const double shade = Uniform(rng, 0.85, 1.12);
    if (look.brick) {
      look.base = Eigen::Vector3d(0.42, 0.12, 0.065) * shade;
    } else if (Uniform(rng, 0, 1) < 0.08) {
      look.base = Eigen::Vector3d(0.70, 0.68, 0.62) * shade;  // bleached board
    } else {
      // One draw at a time (argument order is the compiler's choice); the
      // last first, as g++ has always drawn them.
      const double blue = Uniform(rng, 0.9, 1.1);
      const double red = Uniform(rng, 0.97, 1.03);
      look.base = Eigen::Vector3d(0.47 * red, 0.28, 0.125 * blue) * shade;  // kraft
    }
    for (double& s : look.face_shade) s = Uniform(rng, 0.95, 1.05);
    if (!look.brick) {
      const double r = Uniform(rng, 0, 1);
      look.tape = r < 0.55 ? 1 : r < 0.8 ? 2 : r < 0.9 ? 3 : 0;
      look.tape_half_width = std::min(Uniform(rng, 0.022, 0.026), 0.15 * dims.b);
      look.tape_offset = Uniform(rng, -0.004, 0.004);
      look.tape_flap = std::min(Uniform(rng, 0.05, 0.08), 0.5 * dims.h);
      // Labels (white, barcode and text) and logos (coloured ink), inside faces.
      const int labels = Uniform(rng, 0, 1) < 0.6 ? 1 : (Uniform(rng, 0, 1) < 0.5 ? 2 : 0);
      const int logos = Uniform(rng, 0, 1) < 0.5 ? 1 + (Uniform(rng, 0, 1) < 0.4) : 0;
      const Eigen::Vector3d half = 0.5 * dims.vec();
      for (int k = 0; k < labels + logos; ++k) {
        Print p;
        p.label = k < labels;
        p.seed = Hash(look.seed, static_cast<uint32_t>(k), 3u);
        // Top (+z) twice as likely as each other face.
        const int pick = std::uniform_int_distribution<int>(0, 6)(rng);
        p.face = pick >= 6 ? 4 : pick;
        int a1, a2;
        FaceAxes(p.face, &a1, &a2);
        const double margin = 0.015;
        double lo1 = -half[a1] + margin, hi1 = half[a1] - margin;
        double lo2 = -half[a2] + margin, hi2 = half[a2] - margin;
        if (p.face / 2 == 2 && look.tape != 0) {
          // Beside the tape on the flap faces (a2 is y there).
          const double edge = look.tape_half_width + 0.01;
          if (Uniform(rng, 0, 1) < 0.5) {
            lo2 = look.tape_offset + edge;
          } else {
            hi2 = look.tape_offset - edge;
          }
        }
        double w = p.label ? Uniform(rng, 0.08, 0.15) : Uniform(rng, 0.03, 0.09);
        double h = p.label ? Uniform(rng, 0.06, 0.10) : w * Uniform(rng, 0.5, 1.0);
        if (Uniform(rng, 0, 1) < 0.5) std::swap(w, h);
        w = std::min(w, hi1 - lo1);
        h = std::min(h, hi2 - lo2);
        if (w < 0.03 || h < 0.025) continue;
        p.u0 = Uniform(rng, lo1, hi1 - w);
        p.u1 = p.u0 + w;
        p.v0 = Uniform(rng, lo2, hi2 - h);
        p.v1 = p.v0 + h;
        p.round = !p.label && Uniform(rng, 0, 1) < 0.5;
        static const Eigen::Vector3d kInks[] = {{0.02, 0.03, 0.12},
                                                {0.35, 0.02, 0.02},
                                                {0.02, 0.15, 0.04},
                                                {0.02, 0.02, 0.02},
                                                {0.6, 0.35, 0.01}};
        p.ink = kInks[std::uniform_int_distribution<int>(0, 4)(rng)];
        look.prints.push_back(p);
      }
    }
    boxes_.push_back(look);
  }
  for (size_t j = 0; j < scene.supports.size(); ++j) {
    const SupportPart& part = scene.supports[j];
    PartLook look;
    look.seed = Hash(scene.LookSeed(), static_cast<uint32_t>(j), 13u);
    const double shade = Uniform(rng, 0.8, 1.15);
    if (part.name.find("leg") != std::string::npos) {
      look.base = Eigen::Vector3d(0.05, 0.05, 0.055) * shade;
      look.grain_axis = -1;
    } else if (part.name.find("table") != std::string::npos) {
      look.base = Eigen::Vector3d(0.45, 0.43, 0.38) * shade;
      look.grain_axis = -1;
    } else if (part.name == "block") {
      look.base = Eigen::Vector3d(0.36, 0.26, 0.15) * shade;
      look.grain_axis = -1;
    } else {
      look.base = Eigen::Vector3d(0.50, 0.37, 0.21) * shade;
      const Eigen::Vector3d d = part.dims.vec();
      d.maxCoeff(&look.grain_axis);
    }
    parts_.push_back(look);
  }
  floor_base_ = Eigen::Vector3d(1.0, 0.98, 0.93) * Uniform(rng, 0.14, 0.3);
  floor_seed_ = Hash(scene.LookSeed(), 0xF100u, 17u);
}

Eigen::Vector3d SurfaceTexture::BoxAlbedo(int i, int face, const Eigen::Vector3d& q) const {
  const BoxLook& look = boxes_[i];
  const Eigen::Vector3d& half = caster_.cuboids()[i].half;
  int a1, a2;
  FaceAxes(face, &a1, &a2);
  const double s = q[a1], t = q[a2];
  const double edge = std::min(half[a1] - std::abs(s), half[a2] - std::abs(t));
  const uint32_t fseed = look.seed + static_cast<uint32_t>(face);
  Eigen::Vector3d col = look.base * look.face_shade[face];
  if (look.brick) {
    col *= (0.8 + 0.4 * ValueNoise(s / 0.004, t / 0.004, fseed)) *
           (0.9 + 0.2 * ValueNoise(s / 0.03, t / 0.03, fseed + 99));
    if (edge < 0.002) col *= 0.7 + 0.3 * edge / 0.002;
    return col;
  }
  col *= 0.93 + 0.14 * ValueNoise(s / 0.03, t / 0.03, fseed);  // board blotches
  const int axis = face / 2;
  // Tape along x over the flap faces (+-z) and down the ends (+-x).
  bool on_tape = false;
  const double dy = std::abs(q.y() - look.tape_offset);
  if (look.tape != 0 && dy < look.tape_half_width) {
    on_tape = axis == 2 || (axis == 0 && std::abs(q.z()) > half.z() - look.tape_flap);
  }
  if (on_tape) {
    switch (look.tape) {
      case 1:
        col = Eigen::Vector3d(0.30, 0.15, 0.05) * (0.95 + 0.1 * ValueNoise(s / 0.05, t, fseed));
        break;
      case 2:
        col = col.cwiseProduct(Eigen::Vector3d(0.92, 0.9, 0.82));
        break;
      default:
        col = Eigen::Vector3d(0.74, 0.74, 0.7);
        break;
    }
    if (look.tape_half_width - dy < 0.0015) col *= 0.8;  // the tape's edge
  }
  // The flap seam along the middle of the flap faces, hidden by opaque tape.
  if (axis == 2 && std::abs(q.y()) < 0.0015 && (look.tape == 0 || look.tape == 2)) {
    col *= look.tape == 0 ? 0.4 : 0.65;
  }
  for (const Print& p : look.prints) {
    if (p.face != face || s < p.u0 || s > p.u1 || t < p.v0 || t > p.v1) continue;
    const double ls = (s - p.u0) / (p.u1 - p.u0), lt = (t - p.v0) / (p.v1 - p.v0);
    if (p.label) {
      col = Eigen::Vector3d(0.8, 0.8, 0.78);
      const bool wide = (p.u1 - p.u0) >= (p.v1 - p.v0);
      const double along = wide ? ls : lt, across = wide ? lt : ls;
      if (across > 0.55 && across < 0.88 && along > 0.08 && along < 0.92) {
        const int module = static_cast<int>((along - 0.08) / 0.84 * 95);
        if (Hash(p.seed, static_cast<uint32_t>(module), 5u) & 1u)
          col = Eigen::Vector3d::Constant(0.03);
      } else if (across > 0.1 && across < 0.47 && along > 0.08) {
        const int row = static_cast<int>((across - 0.1) / 0.093);
        const double in_row = (across - 0.1) / 0.093 - row;
        const double len = 0.3 + 0.6 * Hash01(p.seed, static_cast<uint32_t>(row), 9u);
        const int glyph = static_cast<int>(along * 45);
        if (in_row < 0.6 && along < len &&
            Hash01(p.seed, static_cast<uint32_t>(row * 64 + glyph), 21u) < 0.75) {
          col = Eigen::Vector3d::Constant(0.06);
        }
      }
    } else if (!p.round || std::pow(2 * ls - 1, 2) + std::pow(2 * lt - 1, 2) <= 1.0) {
      col = p.ink;
    }
  }
  // Rounded, crushed edges read darker: this draws the seams between boxes.
  if (edge < 0.005) col *= 0.55 + 0.45 * edge / 0.005;
  return col;
}

Eigen::Vector3d SurfaceTexture::PartAlbedo(int part, const Eigen::Vector3d& q) const {
  const PartLook& look = parts_[part];
  Eigen::Vector3d col = look.base;
  if (look.grain_axis < 0) {
    return col * (0.85 + 0.3 * ValueNoise(q.x() / 0.01 + q.z() / 0.013, q.y() / 0.01, look.seed));
  }
  const int a = look.grain_axis;
  const double along = q[a], across = q[(a + 1) % 3] + 0.7 * q[(a + 2) % 3];
  const double wobble = 1.5 * ValueNoise(along / 0.08, across / 0.02, look.seed);
  col *= 1.0 + 0.09 * std::sin(2 * std::numbers::pi * (across / 0.007 + wobble));
  col *= 0.88 + 0.24 * ValueNoise(along / 0.12, across / 0.04, look.seed + 1);
  return col;
}

Eigen::Vector3d SurfaceTexture::FloorAlbedo(const Eigen::Vector3d& w) const {
  return floor_base_ * (0.82 + 0.36 * ValueNoise(w.x() / 0.4, w.y() / 0.4, floor_seed_)) *
         (0.9 + 0.2 * ValueNoise(w.x() / 0.02, w.y() / 0.02, floor_seed_ + 1));
}

Eigen::Vector3d SurfaceTexture::Albedo(const Hit& hit, const Eigen::Vector3d& p) const {
  if (hit.object == kNothing) return Eigen::Vector3d::Zero();
  if (hit.object == kFloor) return FloorAlbedo(world_T_camera_ * p);
  const Cuboid& c = caster_.cuboids()[hit.object];
  const Eigen::Vector3d q = c.cam_R_box.transpose() * (p - c.cam_t_box);
  if (hit.object < caster_.num_boxes()) return BoxAlbedo(hit.object, hit.face, q);
  return PartAlbedo(hit.object - caster_.num_boxes(), q);
}

double SurfaceTexture::Luma(const Hit& hit, const Eigen::Vector3d& p) const {
  const Eigen::Vector3d a = Albedo(hit, p);
  return 0.2126 * a.x() + 0.7152 * a.y() + 0.0722 * a.z();
}

}  // namespace cornerpose::testing::internal
