// A small RGB raster for debug images: pixels, clipped lines, crosses and
// digits. Everything outside the image is dropped, so callers may draw
// anything they project.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace cornerpose {

using Rgb = std::array<uint8_t, 3>;

class Canvas {
 public:
  Canvas(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<uint8_t>& rgb() const { return rgb_; }  // row-major, 3 bytes a pixel

  void Set(int u, int v, const Rgb& colour);
  // A line between two pixel positions (any values, even far off-image).
  void Line(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Rgb& colour);
  // A "+" of the given half size, centred on p.
  void Cross(const Eigen::Vector2d& p, int half_size, const Rgb& colour);
  // A non-negative integer in a 3x5 pixel font, magnified by scale, with its
  // top-left corner at p.
  void Number(const Eigen::Vector2d& p, int value, int scale, const Rgb& colour);

 private:
  int width_;
  int height_;
  std::vector<uint8_t> rgb_;
};

}  // namespace cornerpose
