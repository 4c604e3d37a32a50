#include "common/viz/canvas.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace cornerpose {
namespace {

// Clips segment a-b to the box [lo, hi]^2 (Liang-Barsky); false when it misses.
bool Clip(Eigen::Vector2d* a, Eigen::Vector2d* b, const Eigen::Vector2d& lo,
          const Eigen::Vector2d& hi) {
  const Eigen::Vector2d d = *b - *a;
  double t0 = 0.0, t1 = 1.0;
  const double p[4] = {-d.x(), d.x(), -d.y(), d.y()};
  const double q[4] = {a->x() - lo.x(), hi.x() - a->x(), a->y() - lo.y(), hi.y() - a->y()};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  const Eigen::Vector2d start = *a;
  *a = start + t0 * d;
  *b = start + t1 * d;
  return true;
}

// 3x5 glyphs for 0-9, one row per 3 bits, top row first.
constexpr std::array<std::array<uint8_t, 5>, 10> kDigits = {{
    {7, 5, 5, 5, 7},
    {2, 6, 2, 2, 7},
    {7, 1, 7, 4, 7},
    {7, 1, 7, 1, 7},
    {5, 5, 7, 1, 1},
    {7, 4, 7, 1, 7},
    {7, 4, 7, 5, 7},
    {7, 1, 1, 1, 1},
    {7, 5, 7, 5, 7},
    {7, 5, 7, 1, 7},
}};

}  // namespace

Canvas::Canvas(int width, int height)
    : width_(std::max(width, 0)),
      height_(std::max(height, 0)),
      rgb_(static_cast<size_t>(width_) * height_ * 3, 0) {}

void Canvas::Set(int u, int v, const Rgb& colour) {
  if (u < 0 || v < 0 || u >= width_ || v >= height_) return;
  std::copy(colour.begin(), colour.end(), rgb_.begin() + (static_cast<size_t>(v) * width_ + u) * 3);
}

void Canvas::Line(const Eigen::Vector2d& a_in, const Eigen::Vector2d& b_in, const Rgb& colour) {
  if (!a_in.allFinite() || !b_in.allFinite() || width_ == 0 || height_ == 0) return;
  Eigen::Vector2d a = a_in, b = b_in;
  // Clip first so that a far-off endpoint costs nothing.
  if (!Clip(&a, &b, Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(width_ - 0.5, height_ - 0.5))) {
    return;
  }
  // Bresenham between the rounded endpoints.
  int u0 = static_cast<int>(std::lround(a.x())), v0 = static_cast<int>(std::lround(a.y()));
  const int u1 = static_cast<int>(std::lround(b.x())), v1 = static_cast<int>(std::lround(b.y()));
  const int du = std::abs(u1 - u0), dv = -std::abs(v1 - v0);
  const int su = u0 < u1 ? 1 : -1, sv = v0 < v1 ? 1 : -1;
  int err = du + dv;
  while (true) {
    Set(u0, v0, colour);
    if (u0 == u1 && v0 == v1) break;
    const int e2 = 2 * err;
    if (e2 >= dv) {
      err += dv;
      u0 += su;
    }
    if (e2 <= du) {
      err += du;
      v0 += sv;
    }
  }
}

void Canvas::Cross(const Eigen::Vector2d& p, int half_size, const Rgb& colour) {
  Line(p - Eigen::Vector2d(half_size, 0), p + Eigen::Vector2d(half_size, 0), colour);
  Line(p - Eigen::Vector2d(0, half_size), p + Eigen::Vector2d(0, half_size), colour);
}

void Canvas::Number(const Eigen::Vector2d& p, int value, int scale, const Rgb& colour) {
  if (!p.allFinite() || value < 0 || std::abs(p.x()) > 1e6 || std::abs(p.y()) > 1e6) return;
  const std::string digits = std::to_string(value);
  const int u0 = static_cast<int>(std::lround(p.x())), v0 = static_cast<int>(std::lround(p.y()));
  for (size_t k = 0; k < digits.size(); ++k) {
    const auto& glyph = kDigits[digits[k] - '0'];
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 3; ++col) {
        if (((glyph[row] >> (2 - col)) & 1) == 0) continue;
        for (int dy = 0; dy < scale; ++dy) {
          for (int dx = 0; dx < scale; ++dx) {
            Set(u0 + static_cast<int>(k) * 4 * scale + col * scale + dx, v0 + row * scale + dy,
                colour);
          }
        }
      }
    }
  }
}

}  // namespace cornerpose
