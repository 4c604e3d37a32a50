#include "tests/support/obb.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cornerpose::testing {

std::array<Eigen::Vector3d, 8> BoxCorners(const BoxDims& dims, const Eigen::Isometry3d& pose) {
  std::array<Eigen::Vector3d, 8> corners;
  const Eigen::Vector3d half = 0.5 * dims.vec();
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d s((i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0);
    corners[i] = pose * half.cwiseProduct(s);
  }
  return corners;
}

double ObbSeparation(const BoxDims& a, const Eigen::Isometry3d& world_T_a, const BoxDims& b,
                     const Eigen::Isometry3d& world_T_b) {
  const Eigen::Matrix3d A = world_T_a.linear();
  const Eigen::Matrix3d B = world_T_b.linear();
  const Eigen::Vector3d ha = 0.5 * a.vec();
  const Eigen::Vector3d hb = 0.5 * b.vec();
  const Eigen::Vector3d d = world_T_b.translation() - world_T_a.translation();

  double best = -std::numeric_limits<double>::infinity();
  auto test_axis = [&](const Eigen::Vector3d& axis) {
    const double norm = axis.norm();
    if (norm < 1e-9) return;  // parallel edges: covered by the face axes
    const Eigen::Vector3d n = axis / norm;
    const double ra = (A.transpose() * n).cwiseAbs().dot(ha);
    const double rb = (B.transpose() * n).cwiseAbs().dot(hb);
    best = std::max(best, std::abs(d.dot(n)) - ra - rb);
  };
  for (int i = 0; i < 3; ++i) {
    test_axis(A.col(i));
    test_axis(B.col(i));
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) test_axis(A.col(i).cross(B.col(j)));
  }
  return best;
}

}  // namespace cornerpose::testing
