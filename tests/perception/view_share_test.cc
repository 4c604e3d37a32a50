// The share of a box's outline in the image (internal/view_share.h), which
// scales a returned box's score (DetectorOptions::score_in_view).
#include "common/perception/internal/view_share.h"

#include <gtest/gtest.h>

namespace cornerpose::testing {
namespace {

const CameraIntrinsics kCamera;  // Kinect VGA: 640 x 480, f 525

// A box at `centre` (camera frame), its axes the camera's.
Eigen::Isometry3d At(const Eigen::Vector3d& centre) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = centre;
  return pose;
}

// The camera-frame x at depth z of the image's left (-1) or right (+1) edge.
double EdgeX(double z, int side) {
  const double u = side < 0 ? -0.5 : kCamera.width - 0.5;
  return (u - kCamera.cx) / kCamera.fx * z;
}

TEST(BoxViewShareTest, ABoxWhollyInViewIsOne) {
  EXPECT_DOUBLE_EQ(internal::BoxViewShare(kCamera, At({0.1, -0.05, 1.2}), {0.3, 0.2, 0.15}), 1.0);
}

// A flat plate facing the camera, its centre on the image's edge: its
// outline is a rectangle, half of it in view.
TEST(BoxViewShareTest, APlateCentredOnTheBorderIsHalfInView) {
  const BoxDims plate{0.3, 0.2, 0.001};
  for (int side : {-1, 1}) {
    EXPECT_NEAR(internal::BoxViewShare(kCamera, At({EdgeX(1.2, side), 0.0, 1.2}), plate), 0.5, 0.01)
        << side;
  }
  // A quarter of it when its centre is on the corner.
  const double y_top = (-0.5 - kCamera.cy) / kCamera.fy * 1.2;
  EXPECT_NEAR(internal::BoxViewShare(kCamera, At({EdgeX(1.2, -1), y_top, 1.2}), plate), 0.25, 0.01);
}

// A carton sliding out past the right edge, from its right end on the edge
// (`out` 0) to its left end on it (0.3).
TEST(BoxViewShareTest, TheShareFallsAsTheBoxLeavesTheView) {
  const BoxDims carton{0.3, 0.2, 0.15};
  auto share = [&](double out) {
    return internal::BoxViewShare(kCamera, At({EdgeX(1.2, 1) - 0.15 + out, 0.0, 1.2}), carton);
  };
  double last = 1.0;
  for (double out = 0.0; out <= 0.3; out += 0.05) {
    EXPECT_LE(share(out), last + 1e-9) << out;
    last = share(out);
  }
  EXPECT_GT(share(0.0), 0.8);  // its nearer top face and a side reach past the edge
  EXPECT_NEAR(share(0.15), 0.5, 0.1);
  EXPECT_LT(share(0.3), 0.15);
}

TEST(BoxViewShareTest, OutOfViewOrBehindTheCameraIsZero) {
  const BoxDims carton{0.3, 0.2, 0.15};
  EXPECT_DOUBLE_EQ(internal::BoxViewShare(kCamera, At({3.0, 0.0, 1.2}), carton), 0.0);
  EXPECT_DOUBLE_EQ(internal::BoxViewShare(kCamera, At({0.0, 0.0, -1.0}), carton), 0.0);
  // A corner at or behind the camera: not a box the camera sees whole.
  EXPECT_DOUBLE_EQ(internal::BoxViewShare(kCamera, At({0.0, 0.0, 0.05}), carton), 0.0);
}

}  // namespace
}  // namespace cornerpose::testing
