// The boxes a confirmed one proposes beside it (NeighbourHypotheses): across
// each side of its grasp face in its orientation and turned a quarter, and,
// on a pallet stacked at two heights, the same-orientation ones a layer down.
#include "common/perception/neighbour_hypotheses.h"

#include <gtest/gtest.h>

#include <vector>

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
constexpr double kGap = 0.002;

// A carton lying flat 1.5 m in front of the camera, its grasp face +z
// towards the camera (box z = -camera z).
DetectedBox FlatCarton() {
  DetectedBox b;
  b.grasp_face = BoxFace::kPlusZ;
  b.camera_T_box = Eigen::Isometry3d::Identity();
  b.camera_T_box.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  b.camera_T_box.translation() = Eigen::Vector3d(0.1, -0.05, 1.5);
  return b;
}

bool Has(const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector3d& centre,
         const Eigen::Matrix3d& R) {
  for (const Eigen::Isometry3d& p : poses) {
    if ((p.translation() - centre).norm() < 1e-9 && p.linear().isApprox(R, 1e-9)) return true;
  }
  return false;
}

TEST(NeighbourHypothesesTest, ALayerDownAddsTheSameOrientationOnesABoxHeightLower) {
  const DetectedBox b = FlatCarton();
  const std::vector<Eigen::Isometry3d> level = NeighbourHypotheses(b, kCartonS, kGap);
  const std::vector<Eigen::Isometry3d> both = NeighbourHypotheses(b, kCartonS, kGap, true);
  ASSERT_EQ(level.size(), 12u);  // per side: straight across, and turned flush with either end
  ASSERT_EQ(both.size(), 16u);
  for (const Eigen::Isometry3d& p : level) EXPECT_TRUE(Has(both, p.translation(), p.linear()));
  const Eigen::Matrix3d& R = b.camera_T_box.linear();
  const Eigen::Vector3d& t = b.camera_T_box.translation();
  // Down is away from the camera: the box's -z, camera +z, by h.
  const Eigen::Vector3d down = -kCartonS.h * R.col(2);
  ASSERT_GT(down.z(), 0.0);
  for (const Eigen::Vector3d& across :
       {(kCartonS.l + kGap) * R.col(0), -(kCartonS.l + kGap) * R.col(0),
        (kCartonS.b + kGap) * R.col(1), -(kCartonS.b + kGap) * R.col(1)}) {
    EXPECT_TRUE(Has(both, t + across + down, R)) << across.transpose();
    EXPECT_FALSE(Has(level, t + across + down, R)) << across.transpose();
  }
}

}  // namespace
}  // namespace cornerpose::testing
