#include "common/perception/pose_error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace cornerpose {

std::vector<Eigen::Matrix3d> BoxSymmetries(const BoxDims& dims, double equal_tol_m) {
  std::vector<Eigen::Matrix3d> result;
  std::array<int, 3> perm = {0, 1, 2};  // sorted: identity is enumerated first
  do {
    // Column j sends box axis j onto axis perm[j]; only equal sides may trade.
    bool allowed = true;
    for (int j = 0; j < 3; ++j) {
      if (std::abs(dims[j] - dims[perm[j]]) > equal_tol_m) allowed = false;
    }
    if (!allowed) continue;
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
      for (int j = 0; j < 3; ++j) S(perm[j], j) = (signs >> j & 1) ? -1.0 : 1.0;
      if (S.determinant() > 0.0) result.push_back(S);
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  return result;
}

double RotationAngleDeg(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  // ||I - R||_F = 2 sqrt(2) sin(angle / 2) for a rotation R.
  const double s = (R_a - R_b).norm() / (2.0 * std::sqrt(2.0));
  return 2.0 * std::asin(std::clamp(s, 0.0, 1.0)) * 180.0 / std::numbers::pi;
}

double RotationErrorDeg(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b,
                        const BoxDims& dims) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Matrix3d& S : BoxSymmetries(dims)) {
    best = std::min(best, RotationAngleDeg(R_a, R_b * S));
  }
  return best;
}

double TranslationErrorM(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

PoseError ComparePoses(const Eigen::Isometry3d& camera_T_box_a,
                       const Eigen::Isometry3d& camera_T_box_b, const BoxDims& dims) {
  return {TranslationErrorM(camera_T_box_a, camera_T_box_b),
          RotationErrorDeg(camera_T_box_a.linear(), camera_T_box_b.linear(), dims)};
}

}  // namespace cornerpose
