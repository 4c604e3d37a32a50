// Boxes on the floor lie on it (RestOnFloor): a brick whose face fit came
// out tilted into the floor is turned flat onto it; a brick leaning on one
// edge, one on another box, one tilted further or hardly at all keeps its
// pose. The camera looks straight down at a floor 1.5 m away.
#include "common/perception/floor_rest.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <numbers>
#include <string>
#include <vector>

namespace cornerpose {
namespace {

constexpr BoxDims kBrick{0.19, 0.09, 0.057};
constexpr double kDeg = std::numbers::pi / 180.0;
const Eigen::Vector3d kUp(0.0, 0.0, -1.0);  // the floor's normal, towards the camera
const Eigen::Vector3d kOnFloor(0.0, 0.0, 1.5);

// A brick lying flat with its bottom `lift` above the floor, grasp face +z
// up, then turned by tilt_deg about its long axis through `pivot` (its top
// face's centre, or the long edge of its bottom at -y).
enum class Pivot { kTopCentre, kBottomEdge };
DetectedBox Brick(double tilt_deg, double lift = 0.0, Pivot pivot = Pivot::kTopCentre) {
  DetectedBox box;
  box.grasp_face = BoxFace::kPlusZ;
  box.camera_T_box.linear() = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  box.camera_T_box.translation() = kOnFloor + (lift + kBrick.h / 2.0) * kUp;
  box.grasp_normal_camera = kUp;
  box.grasp_centre_camera = kOnFloor + (lift + kBrick.h) * kUp;
  const Eigen::Vector3d p =
      pivot == Pivot::kTopCentre
          ? box.grasp_centre_camera
          : box.camera_T_box * Eigen::Vector3d(0.0, -kBrick.b / 2.0, -kBrick.h / 2.0);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(tilt_deg * kDeg, Eigen::Vector3d::UnitX()).matrix();
  box.camera_T_box.linear() = r * box.camera_T_box.linear();
  box.camera_T_box.translation() = p + r * (box.camera_T_box.translation() - p);
  box.grasp_centre_camera = p + r * (box.grasp_centre_camera - p);
  box.grasp_normal_camera = r * kUp;
  return box;
}

int Rest(std::vector<DetectedBox>* boxes, const FloorRestOptions& options = {}) {
  return RestOnFloor(kUp, kOnFloor, kBrick, options, boxes);
}

TEST(FloorRestTest, ABrickTiltedIntoTheFloorLiesFlatOnIt) {
  for (const double tilt : {2.5, 6.0, 8.0, -11.0, 13.5}) {  // 2.5: its bottom 1.9 mm in
    std::vector<DetectedBox> boxes{Brick(tilt)};
    const Eigen::Vector3d centre = boxes[0].grasp_centre_camera;
    ASSERT_EQ(Rest(&boxes), 1) << tilt;
    const DetectedBox& b = boxes[0];
    EXPECT_NEAR(b.camera_T_box.linear().col(2).dot(kUp), 1.0, 1e-9) << tilt;
    EXPECT_NEAR(b.grasp_normal_camera.dot(kUp), 1.0, 1e-9) << tilt;
    // Turned about its face centre: that stays, and its bottom now lies
    // on the floor within the few millimetres the tilt moved it.
    EXPECT_TRUE(b.grasp_centre_camera.isApprox(centre, 1e-12));
    const Eigen::Vector3d bottom = b.camera_T_box * Eigen::Vector3d(0.0, 0.0, -kBrick.h / 2.0);
    EXPECT_NEAR(kUp.dot(bottom - kOnFloor), 0.0, 0.002) << tilt;
  }
}

TEST(FloorRestTest, BricksThatDoNotLieOnTheFloorKeepTheirPose) {
  std::vector<DetectedBox> boxes{
      Brick(8.0, 0.0, Pivot::kBottomEdge),  // leaning on one edge: nothing in the floor
      Brick(8.0, 0.10),                     // on another box, 10 cm up
      Brick(20.0),                          // tilted past max_tilt_deg
      Brick(0.5),                           // within min_tilt_deg
      Brick(1.2),                           // its bottom 0.9 mm into the floor: min_dip_m 1
  };
  const std::vector<DetectedBox> before = boxes;
  EXPECT_EQ(Rest(&boxes), 0);
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_TRUE(boxes[i].camera_T_box.isApprox(before[i].camera_T_box, 1e-12)) << i;
  }
  // Off.
  std::vector<DetectedBox> tilted{Brick(8.0)};
  FloorRestOptions off;
  off.max_tilt_deg = 0.0;
  EXPECT_EQ(Rest(&tilted, off), 0);
}

TEST(FloorRestTest, OptionsNameTheFieldTheyReject) {
  EXPECT_TRUE(FloorRestOptions{}.Validate().ok());
  FloorRestOptions o;
  o.max_gap_m = 0.0;
  EXPECT_NE(std::string(o.Validate().message()).find("floor_rest.max_gap_m"), std::string::npos);
  o = FloorRestOptions{};
  o.max_tilt_deg = 45.0;
  EXPECT_NE(std::string(o.Validate().message()).find("floor_rest.max_tilt_deg"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose
