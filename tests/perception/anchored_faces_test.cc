// Faces anchored in the corners of a planar patch that does not tile
// (AnchoredFaces): an L of box tops proposes a face in each of its convex
// corners, none in its notch; the option off proposes nothing.
#include "common/perception/anchored_faces.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/perception/face_proposals.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
constexpr double kZ = 1.2;  // the plane, metres in front of the camera

// A patch facing the camera at kZ: points every `step` metres over a
// 0.6 x 0.4 m rectangle centred on the optical axis, less the quadrant
// x > 0, y > 0 (where a box was taken: an L of three carton tops).
PlanarPatch LPatch(double step = 0.01) {
  PlanarPatch p;
  p.normal = Eigen::Vector3d(0, 0, -1);
  for (double x = -0.3 + step / 2; x < 0.3; x += step) {
    for (double y = -0.2 + step / 2; y < 0.2; y += step) {
      if (x > 0.0 && y > 0.0) continue;
      p.points.emplace_back(x, y, kZ);
    }
  }
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& q : p.points) sum += q;
  p.centroid = sum / static_cast<double>(p.points.size());
  return p;
}

// The centre of a carton lying flat whose top face is the 0.3 x 0.2 m
// rectangle centred at (x, y) on the plane.
Eigen::Vector3d FlatCentre(double x, double y) { return {x, y, kZ + kCartonS.h / 2}; }

// Whether a proposal is that carton: centre within 1.5 cm, its l axis along
// x and its h axis along the plane's normal.
bool Proposes(const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector3d& centre) {
  for (const Eigen::Isometry3d& p : poses) {
    if ((p.translation() - centre).norm() > 0.015) continue;
    if (std::abs(p.linear().col(0).x()) > 0.99 && std::abs(p.linear().col(2).z()) > 0.99) {
      return true;
    }
  }
  return false;
}

AnchoredFaceOptions On() {
  AnchoredFaceOptions o;
  o.enabled = true;
  return o;
}

TEST(AnchoredFacesTest, AnLOfBoxTopsProposesTheBoxInEachConvexCorner) {
  const PlanarPatch patch = LPatch();
  const PlaneRectangle rect = OutlineRectangle(patch);
  ASSERT_NEAR(std::max(rect.width, rect.height), 0.6, 0.02);
  // Neither 0.6 x 0.4 tiling fits the L: the tilings propose nothing here.
  const std::vector<Eigen::Isometry3d> poses =
      AnchoredFaces(patch, rect, 0.01, CameraIntrinsics{}, kCartonS, On());
  ASSERT_FALSE(poses.empty());
  // The three cartons of the L, each anchored in a corner of the outline.
  EXPECT_TRUE(Proposes(poses, FlatCentre(-0.15, -0.10)));
  EXPECT_TRUE(Proposes(poses, FlatCentre(0.15, -0.10)));
  EXPECT_TRUE(Proposes(poses, FlatCentre(-0.15, 0.10)));
  // Nothing whose face centre lies in the notch.
  for (const Eigen::Isometry3d& p : poses) {
    const Eigen::Vector3d face = p.translation();
    EXPECT_FALSE(face.x() > 0.02 && face.y() > 0.02) << face.transpose();
  }
  EXPECT_LE(static_cast<int>(poses.size()), On().max_per_patch);
}

// A corner at the image border is no corner: the patch may go on out of
// view. The same L seen so that its -x end lies past the left border.
TEST(AnchoredFacesTest, ACornerCutByTheImageBorderAnchorsNothing) {
  PlanarPatch patch = LPatch();
  CameraIntrinsics camera;
  // Principal point moved so that x = -0.3 m at 1.2 m projects left of u = 0.
  camera.cx = 100.0;
  const std::vector<Eigen::Isometry3d> poses =
      AnchoredFaces(patch, OutlineRectangle(patch), 0.01, camera, kCartonS, On());
  // The carton whose only convex corner is on the cut end is not proposed;
  // the one beside the notch still is, from its corner at (0, 0.2).
  EXPECT_FALSE(Proposes(poses, FlatCentre(-0.15, -0.10)));
  EXPECT_TRUE(Proposes(poses, FlatCentre(-0.15, 0.10)));
  EXPECT_TRUE(Proposes(poses, FlatCentre(0.15, -0.10)));
}

TEST(AnchoredFacesTest, OffByDefaultAndOffProposesNothing) {
  EXPECT_FALSE(AnchoredFaceOptions{}.enabled);
  const PlanarPatch patch = LPatch();
  EXPECT_TRUE(AnchoredFaces(patch, OutlineRectangle(patch), 0.01, CameraIntrinsics{}, kCartonS,
                            AnchoredFaceOptions{})
                  .empty());
}

TEST(AnchoredFacesTest, APatchFarBiggerThanTheBoxIsNotAnchoredIn) {
  AnchoredFaceOptions o = On();
  o.max_faces = 2;  // the L is four faces' worth of outline
  const PlanarPatch patch = LPatch();
  EXPECT_TRUE(
      AnchoredFaces(patch, OutlineRectangle(patch), 0.01, CameraIntrinsics{}, kCartonS, o).empty());
}

TEST(AnchoredFacesTest, ValidateNamesTheField) {
  AnchoredFaceOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.min_edge = 1.5;
  EXPECT_NE(std::string(o.Validate().message()).find("min_edge=1.5"), std::string::npos);
  o = AnchoredFaceOptions{};
  o.max_per_patch = 0;
  EXPECT_NE(std::string(o.Validate().message()).find("max_per_patch=0"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose::testing
