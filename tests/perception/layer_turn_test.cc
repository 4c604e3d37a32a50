// Shared layer turns (AlignToLayerTurns): a box touching at least
// min_agreeing boxes on its plane that agree on their in-plane turn takes
// the layer's; a box alone, in a layer that does not agree, on another
// plane, or turned past max_turn_deg keeps its own. Boxes as the detector
// returns them, lying flat 1.5 m in front of the camera, their grasp face
// towards it.
#include "common/perception/layer_turn.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace cornerpose {
namespace {

constexpr BoxDims kBrick{0.19, 0.09, 0.057};
constexpr double kDeg = std::numbers::pi / 180.0;

// A brick of the layer's grid cell (i, j) (the grid turned by grid_deg in
// the camera's image plane), its face centre at depth z, turned by turn_deg
// about its face's normal.
DetectedBox Brick(int i, int j, double turn_deg, double grid_deg = 20.0, double z = 1.5) {
  const Eigen::Matrix3d grid = Eigen::AngleAxisd(grid_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                               Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();  // +z to the camera
  const Eigen::Vector3d centre =
      Eigen::Vector3d(0.0, 0.0, z) + grid * Eigen::Vector3d(i * kBrick.l, j * kBrick.b, 0.0);
  DetectedBox box;
  box.grasp_face = BoxFace::kPlusZ;
  box.grasp_normal_camera = -Eigen::Vector3d::UnitZ();
  box.grasp_centre_camera = centre;
  box.camera_T_box.linear() =
      Eigen::AngleAxisd(turn_deg * kDeg, box.grasp_normal_camera).toRotationMatrix() * grid;
  box.camera_T_box.translation() = centre - box.grasp_normal_camera * kBrick.h / 2.0;
  return box;
}

// The in-plane turn of `box` against the grid's (mod 90 degrees).
double TurnAgainstGrid(const DetectedBox& box, double grid_deg = 20.0) {
  const Eigen::Vector3d a = box.camera_T_box.linear().col(0);
  const double deg = std::atan2(a.y(), a.x()) / kDeg - grid_deg;
  return std::remainder(deg, 90.0);
}

// A 3 x 2 layer of bricks turned by `turns` (one per brick) against the
// grid.
std::vector<DetectedBox> Layer(const std::vector<double>& turns) {
  std::vector<DetectedBox> boxes;
  boxes.reserve(turns.size());
  for (int k = 0; k < static_cast<int>(turns.size()); ++k) {
    boxes.push_back(Brick(k % 3, k / 3, turns[k]));
  }
  return boxes;
}

TEST(LayerTurnTest, ABoxTurnedAgainstItsLayerTakesTheLayersTurn) {
  // Brick 1 (in the layer's middle row: it touches all five) came out 9
  // degrees off; the others within a degree of the grid.
  std::vector<DetectedBox> boxes = Layer({0.5, 9.0, -0.5, 0.0, 0.8, -0.3});
  const std::vector<DetectedBox> before = boxes;
  EXPECT_EQ(AlignToLayerTurns(kBrick, LayerTurnOptions(), &boxes), 1);
  EXPECT_LT(std::abs(TurnAgainstGrid(boxes[1])), 0.5);
  // Turned about its own face centre: the face's centre and plane stay.
  const Eigen::Vector3d top = Eigen::Vector3d::UnitZ() * kBrick.h / 2.0;
  EXPECT_LT((boxes[1].camera_T_box * top - before[1].grasp_centre_camera).norm(), 1e-9);
  EXPECT_EQ(boxes[1].grasp_normal_camera, before[1].grasp_normal_camera);
  EXPECT_LT((boxes[1].camera_T_box.linear().col(2) - before[1].camera_T_box.linear().col(2)).norm(),
            1e-9);
  for (int k : {0, 2, 3, 4, 5}) {
    EXPECT_TRUE(boxes[k].camera_T_box.isApprox(before[k].camera_T_box)) << k;
  }
}

TEST(LayerTurnTest, TurnsAreKnownModuloAQuarter) {
  // An interlocked layer: two neighbours lie turned a quarter; brick 1 is
  // 4 degrees off both ways of reading them.
  std::vector<DetectedBox> boxes = Layer({90.0, 4.0, -90.3, 0.2, 89.6, 0.0});
  EXPECT_EQ(AlignToLayerTurns(kBrick, LayerTurnOptions(), &boxes), 1);
  EXPECT_LT(std::abs(TurnAgainstGrid(boxes[1])), 0.5);
}

TEST(LayerTurnTest, BoxesThatCannotShareATurnKeepTheirOwn) {
  const LayerTurnOptions defaults;
  // Too few: two agreeing neighbours.
  std::vector<DetectedBox> three = Layer({0.0, 6.0, 0.0});
  const std::vector<DetectedBox> three_before = three;
  EXPECT_EQ(AlignToLayerTurns(kBrick, defaults, &three), 0);
  EXPECT_TRUE(three[1].camera_T_box.isApprox(three_before[1].camera_T_box));
  // A heap, not a layer: the neighbours disagree by more than agree_deg.
  std::vector<DetectedBox> spread = Layer({-8.0, 6.0, 3.0, 14.0, 0.0, -20.0});
  EXPECT_EQ(AlignToLayerTurns(kBrick, defaults, &spread), 0);
  // Turned past max_turn_deg: not lying in the layer's pattern.
  std::vector<DetectedBox> askew = Layer({0.0, 20.0, 0.0, 0.5, -0.5, 0.0});
  EXPECT_EQ(AlignToLayerTurns(kBrick, defaults, &askew), 0);
  // Within min_turn_deg: the layer's own spread.
  std::vector<DetectedBox> close = Layer({0.0, 1.5, 0.0, 0.5, -0.5, 0.0});
  EXPECT_EQ(AlignToLayerTurns(kBrick, defaults, &close), 0);
  // On another plane: brick 1 lies 3 cm higher (a box on the layer).
  std::vector<DetectedBox> higher = Layer({0.0, 6.0, 0.0, 0.5, -0.5, 0.0});
  higher[1] = Brick(1, 0, 6.0);
  higher[1].grasp_centre_camera.z() -= 0.03;
  higher[1].camera_T_box.translation().z() -= 0.03;
  EXPECT_EQ(AlignToLayerTurns(kBrick, defaults, &higher), 0);
  // Off.
  LayerTurnOptions off;
  off.min_agreeing = 0;
  std::vector<DetectedBox> layer = Layer({0.5, 9.0, -0.5, 0.0, 0.8, -0.3});
  EXPECT_EQ(AlignToLayerTurns(kBrick, off, &layer), 0);
}

TEST(LayerTurnTest, OptionsNameTheFieldTheyReject) {
  auto rejects = [](LayerTurnOptions o, const std::string& field) {
    const absl::Status s = o.Validate();
    EXPECT_FALSE(s.ok()) << field;
    EXPECT_NE(s.message().find(field), std::string::npos) << s.message();
  };
  EXPECT_TRUE(LayerTurnOptions().Validate().ok());
  LayerTurnOptions o;
  o.min_agreeing = -1;
  rejects(o, "layer_turn.min_agreeing");
  o = LayerTurnOptions();
  o.agree_deg = 0.0;
  rejects(o, "layer_turn.agree_deg");
  o = LayerTurnOptions();
  o.max_turn_deg = std::nan("");
  rejects(o, "layer_turn.max_turn_deg");
  o = LayerTurnOptions();
  o.plane_tolerance_m = 0.5;
  rejects(o, "layer_turn.plane_tolerance_m");
}

}  // namespace
}  // namespace cornerpose
