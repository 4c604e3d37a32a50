// Shared layer planes (AlignToLayerPlanes): boxes side by side on one plane
// take the plane fitted through all their faces; a box alone, one tilted
// beyond max_angle_deg, or one standing higher keeps its own. Exact depth
// from the test generator, so the fitted plane is the true one.
#include "common/perception/layer_plane.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "common/perception/camera_model.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kBrick{0.19, 0.09, 0.057};

SceneBox Flat(double x, double y, double z_bottom = 0.0) {
  SceneBox b;
  b.dims = kBrick;
  b.world_T_box.translation() = Eigen::Vector3d(x, y, z_bottom + kBrick.h / 2.0);
  return b;
}

struct Layer {
  RenderedScene rendered;
  DepthImage depth;
};

// A 2 x 3 layer of touching bricks (and `extra` beside it), seen from 1.5 m,
// the camera tilted and turned off the grid.
Layer RenderLayer(std::vector<SceneBox> extra = {}) {
  Scene scene;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) scene.boxes.push_back(Flat(i * kBrick.l, j * kBrick.b));
  }
  for (const SceneBox& b : extra) scene.boxes.push_back(b);
  scene.camera = CameraIntrinsics{};
  scene.world_T_camera =
      LookAtCamera(Eigen::Vector3d(kBrick.l / 2, kBrick.b, 0.0), 1.5, 10.0, 20.0, 0.0);
  NoiseOptions exact;
  exact.enabled = false;
  Layer l;
  l.rendered = Render(scene, exact);
  l.depth = MakeDepthImage(l.rendered.cloud, l.rendered.camera);
  return l;
}

double Deg(double rad) { return rad * 180.0 / std::numbers::pi; }

// The box as the detector returns it, its face turned by `tilt_deg` about
// an in-plane axis at `dir_deg` (about its face centre).
DetectedBox Returned(const GroundTruthBox& gt, double tilt_deg, double dir_deg) {
  DetectedBox box;
  box.grasp_face = gt.grasp_face;
  const int axis = static_cast<int>(gt.grasp_face) / 2;
  const double sign = static_cast<int>(gt.grasp_face) % 2 == 0 ? 1.0 : -1.0;
  const Eigen::Vector3d n = sign * gt.camera_T_box.linear().col(axis);
  const Eigen::Vector3d centre =
      gt.camera_T_box * (sign * Eigen::Vector3d::Unit(axis) * kBrick[axis] / 2.0);
  const Eigen::Vector3d in_plane =
      std::cos(dir_deg * std::numbers::pi / 180.0) * gt.camera_T_box.linear().col((axis + 1) % 3) +
      std::sin(dir_deg * std::numbers::pi / 180.0) * gt.camera_T_box.linear().col((axis + 2) % 3);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(tilt_deg * std::numbers::pi / 180.0, in_plane).toRotationMatrix();
  box.camera_T_box.linear() = turn * gt.camera_T_box.linear();
  box.grasp_normal_camera = turn * n;
  box.grasp_centre_camera = centre;
  box.camera_T_box.translation() = centre - box.grasp_normal_camera * kBrick[axis] / 2.0;
  return box;
}

Eigen::Vector3d TrueNormal(const GroundTruthBox& gt) {
  const int axis = static_cast<int>(gt.grasp_face) / 2;
  const double sign = static_cast<int>(gt.grasp_face) % 2 == 0 ? 1.0 : -1.0;
  return sign * gt.camera_T_box.linear().col(axis);
}

TEST(LayerPlaneTest, BoxesSideBySideTakeTheLayersPlane) {
  const Layer l = RenderLayer();
  std::vector<DetectedBox> boxes;
  for (size_t i = 0; i < 6; ++i) {
    boxes.push_back(Returned(l.rendered.boxes[i], 3.0 + 0.5 * i, 60.0 * i));
  }
  const std::vector<DetectedBox> before = boxes;
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 6);
  for (size_t i = 0; i < 6; ++i) {
    const Eigen::Vector3d n = TrueNormal(l.rendered.boxes[i]);
    EXPECT_LT(Deg(std::acos(std::min(1.0, boxes[i].grasp_normal_camera.dot(n)))), 0.3) << i;
    // The whole pose turned with the normal (the box's own axis is it), about
    // the face centre; the in-plane turn stays the box's own.
    const int axis = static_cast<int>(boxes[i].grasp_face) / 2;
    EXPECT_LT((boxes[i].camera_T_box.linear().col(axis) - n).norm(), 0.01) << i;
    EXPECT_LT((boxes[i].camera_T_box * (Eigen::Vector3d::Unit(axis) * kBrick[axis] / 2.0) -
               before[i].grasp_centre_camera)
                  .norm(),
              1e-9)
        << i;
    EXPECT_EQ(boxes[i].grasp_centre_camera, before[i].grasp_centre_camera);
  }
}

TEST(LayerPlaneTest, ABoxAloneOrTurnedOffTheLayerKeepsItsOwnPlane) {
  const Layer l = RenderLayer();
  // Alone: nothing to share.
  std::vector<DetectedBox> one = {Returned(l.rendered.boxes[0], 4.0, 0.0)};
  const DetectedBox alone = one[0];
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &one), 0);
  EXPECT_TRUE(one[0].camera_T_box.isApprox(alone.camera_T_box));
  // Three boxes of the layer and one returned tilted by 30 degrees: past
  // adopt_angle_deg, that one keeps its own plane, the others take the
  // layer's.
  std::vector<DetectedBox> boxes;
  for (size_t i = 0; i < 3; ++i) boxes.push_back(Returned(l.rendered.boxes[i], 2.0, 90.0 * i));
  boxes.push_back(Returned(l.rendered.boxes[3], 30.0, 30.0));
  const DetectedBox askew = boxes[3];
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 3);
  EXPECT_TRUE(boxes[3].camera_T_box.isApprox(askew.camera_T_box));
  // Off: nothing turns.
  LayerPlaneOptions off;
  off.max_angle_deg = 0.0;
  std::vector<DetectedBox> again = {Returned(l.rendered.boxes[0], 2.0, 0.0),
                                    Returned(l.rendered.boxes[1], 2.0, 90.0)};
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, off, &again), 0);
}

TEST(LayerPlaneTest, AFaceTiltedByItsFitAloneTakesTheLayersPlane) {
  // Returned 15 degrees off (an active-stereo camera's correlated noise
  // over a brick's narrow face) while its pixels lie on the layer: past
  // max_angle_deg it joins no group, but it touches the group and its
  // pixels fit the layer's plane, so it takes it (box 3 at the layer's
  // side, box 5 at its corner).
  const Layer l = RenderLayer();
  for (const int tilted : {3, 5}) {
    std::vector<DetectedBox> boxes;
    for (int i = 0; i < 6; ++i) {
      boxes.push_back(Returned(l.rendered.boxes[i], i == tilted ? 15.0 : 2.0, 60.0 * i));
    }
    EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 6) << tilted;
    const Eigen::Vector3d n = TrueNormal(l.rendered.boxes[tilted]);
    EXPECT_LT(Deg(std::acos(std::min(1.0, boxes[tilted].grasp_normal_camera.dot(n)))), 0.3)
        << tilted;
    // With adopt_angle_deg at max_angle_deg it keeps its own.
    LayerPlaneOptions strict;
    strict.adopt_angle_deg = strict.max_angle_deg;
    std::vector<DetectedBox> again;
    for (int i = 0; i < 6; ++i) {
      again.push_back(Returned(l.rendered.boxes[i], i == tilted ? 15.0 : 2.0, 60.0 * i));
    }
    EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, strict, &again), 5) << tilted;
  }
}

TEST(LayerPlaneTest, ASmallGroupTiltedByItsNoiseTakesTheBiggerGroupsPlane) {
  // Depth noise of 5 mm everywhere and, over bricks 4 and 5, a bump that
  // tilts their pixels by about 5 degrees (an active-stereo camera's smoothed
  // noise over a few bricks at 2 m); returned 14 degrees off, those two
  // group apart from the other four and fit the bump's plane. Their pixels
  // still fit the bigger group's plane about as well: they take it.
  Layer l = RenderLayer();
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.005f);
  const GroundTruthBox& g4 = l.rendered.boxes[4];
  const Eigen::Vector3d n4 = TrueNormal(g4);
  const Eigen::Vector3d across = g4.camera_T_box.linear().col(0);  // the bump's slope
  const Eigen::Vector3d centre = g4.camera_T_box.translation();
  const double slope = std::tan(3.5 * std::numbers::pi / 180.0);
  for (size_t i = 0; i < l.depth.z.size(); ++i) {
    float& z = l.depth.z[i];
    if (!(z > 0.0f)) continue;
    if (l.rendered.instance[i] == 5 || l.rendered.instance[i] == 6) {
      const Eigen::Vector3d p = l.rendered.cloud.xyz[i].cast<double>();
      z += static_cast<float>(slope * (p - centre).dot(across) * -n4.z());
    }
    z += noise(rng);
  }
  auto returned = [&] {
    std::vector<DetectedBox> boxes;
    for (int i = 0; i < 6; ++i) {
      boxes.push_back(Returned(l.rendered.boxes[i], i >= 4 ? 14.0 : 1.0, i >= 4 ? 90.0 : 60.0 * i));
    }
    return boxes;
  };
  std::vector<DetectedBox> boxes = returned();
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 6);
  std::vector<DetectedBox> apart = returned();
  LayerPlaneOptions no_merge;
  no_merge.merge_groups = false;
  AlignToLayerPlanes(l.depth, kBrick, no_merge, &apart);
  for (int i : {4, 5}) {
    const Eigen::Vector3d n = TrueNormal(l.rendered.boxes[i]);
    EXPECT_LT(Deg(std::acos(std::min(1.0, boxes[i].grasp_normal_camera.dot(n)))), 2.0) << i;
    EXPECT_GT(Deg(std::acos(std::min(1.0, apart[i].grasp_normal_camera.dot(n)))), 3.0) << i;
  }
}

// Renders the layer with `askew` beside it, returns every box at its true
// pose, and expects the layer's six to take its plane and `askew` to keep
// its own.
void ExpectKeepsItsPlane(const SceneBox& askew) {
  const Layer l = RenderLayer({askew});
  ASSERT_EQ(l.rendered.boxes.size(), 7u);
  std::vector<DetectedBox> boxes;
  for (int i = 0; i < 7; ++i) boxes.push_back(Returned(l.rendered.boxes[i], 0.0, 0.0));
  const DetectedBox before = boxes[6];
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 6);
  EXPECT_TRUE(boxes[6].camera_T_box.isApprox(before.camera_T_box));
}

TEST(LayerPlaneTest, ABrickReallyTiltedBesideTheLayerKeepsItsPlane) {
  // A brick beside the layer, turned 15 degrees about its long axis (one
  // long side 2.3 cm higher than the other) and resting on the floor by its
  // lower long edge: its face centre 1 cm over the layer's plane (on it,
  // within plane_tolerance_m, but as high as the tilt lifts it), and its
  // pixels do not fit that plane.
  SceneBox askew = Flat(2 * kBrick.l, 0.0);
  const double tilt = 15.0 * std::numbers::pi / 180.0;
  askew.world_T_box.linear() = Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
  askew.world_T_box.translation().z() =
      kBrick.b / 2.0 * std::sin(tilt) + kBrick.h / 2.0 * std::cos(tilt);
  ExpectKeepsItsPlane(askew);
}

TEST(LayerPlaneTest, ABrickTiltedIntoAGapBesideTheLayerKeepsItsPlane) {
  // As above, but turned about its own centre: its face centre lies on the
  // layer's plane and one long side 1 cm below it (into a gap beside the
  // layer, as a heap's box tilts). Its pixels fit their own plane exactly
  // and the layer's not at all: it keeps its tilt, however low it lies.
  SceneBox askew = Flat(2 * kBrick.l, 0.0);
  askew.world_T_box.linear() =
      Eigen::AngleAxisd(15.0 * std::numbers::pi / 180.0, Eigen::Vector3d::UnitX())
          .toRotationMatrix();
  ExpectKeepsItsPlane(askew);
}

TEST(LayerPlaneTest, AFaceTiltedByNoiseWithItsCentreInTheLayerTakesItsPlane) {
  // Depth noise of 5 mm everywhere and, over a brick lying flat beside the
  // layer, a blob of correlated noise that tilts its pixels by 20 degrees
  // about its long axis (an active-stereo camera at 2 m); returned so
  // tilted. Its pixels fit the layer's plane 1.8 times worse than their own
  // (past max_rms_ratio), but its face centre lies on the layer's plane,
  // where a brick so tilted would have a long side 1.5 cm inside the layer
  // (LayerPlaneOptions::rest_share): within rest_max_rms_ratio, it takes
  // the layer's plane.
  Layer l = RenderLayer({Flat(2 * kBrick.l, 0.0)});
  ASSERT_EQ(l.rendered.boxes.size(), 7u);
  const GroundTruthBox& g = l.rendered.boxes[6];
  const Eigen::Vector3d n = TrueNormal(g);
  const Eigen::Vector3d across = g.camera_T_box.linear().col(1);  // the 9 cm axis
  const Eigen::Vector3d centre = g.camera_T_box.translation();
  const double slope = std::tan(20.0 * std::numbers::pi / 180.0);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.005f);
  for (size_t i = 0; i < l.depth.z.size(); ++i) {
    float& z = l.depth.z[i];
    if (!(z > 0.0f)) continue;
    if (l.rendered.instance[i] == 7) {
      const Eigen::Vector3d p = l.rendered.cloud.xyz[i].cast<double>();
      z += static_cast<float>(slope * (p - centre).dot(across) * -n.z());
    }
    z += noise(rng);
  }
  auto returned = [&] {
    std::vector<DetectedBox> boxes;
    for (int i = 0; i < 6; ++i) boxes.push_back(Returned(l.rendered.boxes[i], 1.0, 60.0 * i));
    // Tilted as its pixels are: about the long axis, toward the 9 cm one.
    boxes.push_back(Returned(g, -20.0, 0.0));
    return boxes;
  };
  std::vector<DetectedBox> boxes = returned();
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 7);
  EXPECT_LT(Deg(std::acos(std::min(1.0, boxes[6].grasp_normal_camera.dot(n)))), 1.0);
  // Asking for max_rms_ratio always: it keeps its tilt.
  LayerPlaneOptions fit_only;
  fit_only.rest_share = 0.0;
  std::vector<DetectedBox> again = returned();
  const DetectedBox tilted = again[6];
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, fit_only, &again), 6);
  EXPECT_TRUE(again[6].camera_T_box.isApprox(tilted.camera_T_box));
}

TEST(LayerPlaneTest, ABoxOnTopOfTheLayerIsNotOnItsPlane) {
  // A brick lying on the layer's first brick: touching in the image, a
  // brick's height nearer the camera.
  const Layer l = RenderLayer({Flat(0.0, 0.0, kBrick.h)});
  ASSERT_EQ(l.rendered.boxes.size(), 7u);
  std::vector<DetectedBox> boxes = {Returned(l.rendered.boxes[6], 3.0, 0.0),
                                    Returned(l.rendered.boxes[1], 3.0, 120.0)};
  const std::vector<DetectedBox> before = boxes;
  EXPECT_EQ(AlignToLayerPlanes(l.depth, kBrick, LayerPlaneOptions(), &boxes), 0);
  EXPECT_TRUE(boxes[0].camera_T_box.isApprox(before[0].camera_T_box));
}

// Two bricks side by side along their short axis, turned by tilt_a and
// tilt_b degrees about it, their returned poses exact.
struct Pair {
  RenderedScene rendered;
  DepthImage depth;
  std::vector<DetectedBox> boxes;
};
Pair RenderPair(double tilt_a, double tilt_b) {
  Scene scene;
  for (double tilt : {tilt_a, tilt_b}) {
    SceneBox b = Flat(0.0, scene.boxes.size() * kBrick.b, 0.02);
    b.world_T_box.linear() =
        Eigen::AngleAxisd(tilt * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY())
            .toRotationMatrix();
    scene.boxes.push_back(b);
  }
  scene.camera = CameraIntrinsics{};
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d(0.0, kBrick.b / 2, 0.0), 1.2, 5.0, 0.0, 0.0);
  NoiseOptions exact;
  exact.enabled = false;
  Pair p;
  p.rendered = Render(scene, exact);
  p.depth = MakeDepthImage(p.rendered.cloud, p.rendered.camera);
  p.boxes = {Returned(p.rendered.boxes[0], 0.0, 0.0), Returned(p.rendered.boxes[1], 0.0, 0.0)};
  return p;
}

TEST(LayerPlaneTest, TwoFacesTiltedAgainstEachOtherDoNotShareAPlane) {
  // Turned 5 degrees the opposite ways (a twist in a heap): their centres
  // lie on each other's planes and their normals are 10 degrees apart, but
  // no one plane fits both faces.
  Pair twisted = RenderPair(5.0, -5.0);
  ASSERT_GT(twisted.boxes[0].grasp_normal_camera.dot(twisted.boxes[1].grasp_normal_camera),
            std::cos(11.0 * std::numbers::pi / 180.0));
  const std::vector<DetectedBox> before = twisted.boxes;
  EXPECT_EQ(AlignToLayerPlanes(twisted.depth, kBrick, LayerPlaneOptions(), &twisted.boxes), 0);
  EXPECT_TRUE(twisted.boxes[1].camera_T_box.isApprox(before[1].camera_T_box));
  // Turned the same way they are one plane.
  Pair same = RenderPair(5.0, 5.0);
  EXPECT_EQ(AlignToLayerPlanes(same.depth, kBrick, LayerPlaneOptions(), &same.boxes), 2);
}

TEST(LayerPlaneTest, ValidateNamesTheField) {
  LayerPlaneOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.max_angle_deg = 45.0;
  EXPECT_NE(o.Validate().message().find("layer_plane.max_angle_deg"), std::string::npos);
  o = LayerPlaneOptions();
  o.plane_tolerance_m = 0.0;
  EXPECT_NE(o.Validate().message().find("layer_plane.plane_tolerance_m"), std::string::npos);
  o = LayerPlaneOptions();
  o.adopt_angle_deg = 50.0;
  EXPECT_NE(o.Validate().message().find("layer_plane.adopt_angle_deg"), std::string::npos);
  o = LayerPlaneOptions();
  o.rest_share = 1.5;
  EXPECT_NE(o.Validate().message().find("layer_plane.rest_share"), std::string::npos);
  o = LayerPlaneOptions();
  o.rest_max_rms_ratio = 0.5;
  EXPECT_NE(o.Validate().message().find("layer_plane.rest_max_rms_ratio"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose::testing
