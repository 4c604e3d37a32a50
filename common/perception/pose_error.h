// Symmetry-aware comparison of cuboid poses. A box of known size has 4, 8 or
// 24 rotations that leave it unchanged, so two poses that differ by one of
// them describe the same physical box and must compare equal.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "common/perception/types.h"

namespace cornerpose {

// The proper rotations (signed permutation matrices, det +1) that map the
// cuboid onto itself: 4 for distinct sides, 8 with two equal sides, 24 for a
// cube. Sides closer than equal_tol_m count as equal. Identity comes first.
std::vector<Eigen::Matrix3d> BoxSymmetries(const BoxDims& dims, double equal_tol_m = 1e-4);

// Angle between two rotations, degrees, computed as
// 2 asin(||R_a - R_b||_F / (2 sqrt 2)), which stays accurate near 0.
double RotationAngleDeg(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b);

// min over the box symmetries S of the angle between R_a and R_b * S, degrees.
double RotationErrorDeg(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b,
                        const BoxDims& dims);

// Distance between the two origins (box centroids), metres.
double TranslationErrorM(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);

struct PoseError {
  double translation_m = 0.0;
  double rotation_deg = 0.0;
};

PoseError ComparePoses(const Eigen::Isometry3d& camera_T_box_a,
                       const Eigen::Isometry3d& camera_T_box_b, const BoxDims& dims);

}  // namespace cornerpose
