#include "common/viz/box_wireframe.h"

namespace cornerpose {

std::array<Eigen::Vector3d, 8> BoxCornersCamera(const Eigen::Isometry3d& camera_T_box,
                                                const BoxDims& dims) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d box((i & 1 ? 0.5 : -0.5) * dims.l, (i & 2 ? 0.5 : -0.5) * dims.b,
                              (i & 4 ? 0.5 : -0.5) * dims.h);
    corners[i] = camera_T_box * box;
  }
  return corners;
}

const std::array<std::pair<int, int>, 12>& BoxEdges() {
  static const std::array<std::pair<int, int>, 12> kEdges = [] {
    std::array<std::pair<int, int>, 12> edges;
    int k = 0;
    for (int i = 0; i < 8; ++i) {
      for (int bit = 1; bit < 8; bit <<= 1) {
        if ((i & bit) == 0) edges[k++] = {i, i | bit};
      }
    }
    return edges;
  }();
  return kEdges;
}

}  // namespace cornerpose
