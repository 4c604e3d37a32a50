// Face-first proposals: planar patches, the tilings of a patch's outline,
// the choice between tilings, and the colour seam cue.
#include "common/perception/face_proposals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "common/perception/camera_model.h"
#include "common/perception/internal/parallel.h"
#include "common/perception/planar_patches.h"
#include "common/perception/seam_cues.h"

namespace cornerpose {
namespace {

constexpr double kTop = 1.2;     // camera to the layer's top, metres
constexpr double kFloor = 1.35;  // camera to the floor

// A camera looking straight down at a rectangular layer (its top a plane at
// kTop, turned by yaw about the optical axis) on a floor. Exact depth.
struct LayerFrame {
  double width = 0.9, height = 0.4;  // layer outline, metres
  double yaw_deg = 20.0;
  Eigen::Vector2d centre{0.02, -0.03};
  DepthImage image;

  Eigen::Vector2d ToLayer(double x, double y) const {
    const double c = std::cos(yaw_deg * M_PI / 180), s = std::sin(yaw_deg * M_PI / 180);
    const Eigen::Vector2d d(x - centre.x(), y - centre.y());
    return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
  }
  Eigen::Vector3d FromLayer(double a, double b, double z) const {
    const double c = std::cos(yaw_deg * M_PI / 180), s = std::sin(yaw_deg * M_PI / 180);
    return {centre.x() + c * a - s * b, centre.y() + s * a + c * b, z};
  }
  void Render() {
    image.camera = CameraIntrinsics{};
    const CameraIntrinsics& k = image.camera;
    image.z.assign(static_cast<size_t>(k.width) * k.height, 0.0f);
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const Eigen::Vector3d ray = PixelRay(k, u, v);
        const Eigen::Vector2d q = ToLayer(ray.x() * kTop, ray.y() * kTop);
        const bool on_layer = std::abs(q.x()) <= width / 2 && std::abs(q.y()) <= height / 2;
        image.z[static_cast<size_t>(v) * k.width + u] =
            static_cast<float>(on_layer ? kTop : kFloor);
      }
    }
  }
  // Grey image: cardboard (150) with dark seam lines (seam_grey) at the
  // given layer coordinates, 4 mm wide, and optional rectangles; with
  // grain, per-pixel noise of that sigma (grey levels); with stripes,
  // lines stripe_dark darker every stripe_period_m along a, one at a = 0
  // (wood grain).
  float seam_grey = 60.0f;
  double seam_slope = 0.0;  // seams along a run at a + seam_slope b
  double grain = 0.0;
  double stripe_period_m = 0.0;
  float stripe_dark = 0.0f;
  void Paint(const std::vector<double>& seams_a, const std::vector<double>& seams_b,
             const std::vector<Eigen::Vector4d>& dark_rects = {}) {
    const CameraIntrinsics& k = image.camera;
    image.grey.assign(static_cast<size_t>(k.width) * k.height, 150.0f);
    std::mt19937 rng(11);
    std::normal_distribution<float> noise(0.0f, static_cast<float>(grain));
    const double half_line = 0.002;  // 4 mm wide lines: ~2 px at 1.2 m
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const Eigen::Vector3d ray = PixelRay(k, u, v);
        const Eigen::Vector2d q = ToLayer(ray.x() * kTop, ray.y() * kTop);
        float& g = image.grey[static_cast<size_t>(v) * k.width + u];
        if (std::abs(q.x()) > width / 2 || std::abs(q.y()) > height / 2) {
          g = 90.0f;  // the floor
          continue;
        }
        if (stripe_period_m > 0.0) {
          const double phase = std::remainder(q.x(), stripe_period_m);
          if (std::abs(phase) < half_line / 2) g -= stripe_dark;
        }
        for (double a : seams_a) {
          if (std::abs(q.x() - a - seam_slope * q.y()) < half_line) g = seam_grey;
        }
        for (double b : seams_b) {
          if (std::abs(q.y() - b) < half_line) g = seam_grey;
        }
        if (grain > 0.0) g += noise(rng);
        for (const Eigen::Vector4d& r : dark_rects) {  // a0, b0, a1, b1
          if (q.x() >= r[0] && q.x() <= r[2] && q.y() >= r[1] && q.y() <= r[3]) g = 40.0f;
        }
      }
    }
  }
};

const BoxDims kCarton{0.30, 0.20, 0.15};

TEST(TilingsOfTest, AWholeNumberOfFacesAndFewestFirst) {
  const FaceProposalOptions o;
  // 3 x 2 cartons lying flat: 0.9 x 0.4.
  std::vector<FaceTiling> t = TilingsOf(0.9 + 0.004, 0.4 + 0.002, kCarton, o);
  ASSERT_FALSE(t.empty());
  EXPECT_EQ(t[0].normal_axis, 2);
  EXPECT_EQ(t[0].count_u, 3);
  EXPECT_EQ(t[0].count_v, 2);
  EXPECT_TRUE(t.size() == 1 || t[1].tiles() > t[0].tiles());
  // One carton's top: one tile first (the 2 x 1 of side faces comes later).
  t = TilingsOf(0.30, 0.20, kCarton, o);
  ASSERT_GE(t.size(), 2u);
  EXPECT_EQ(t[0].tiles(), 1);
  EXPECT_GT(t[1].tiles(), 1);
  // 0.6 x 0.6 tiles as 2 x 3 and as 3 x 2 cartons: two tilings, six each.
  t = TilingsOf(0.6, 0.6, kCarton, o);
  ASSERT_GE(t.size(), 2u);
  EXPECT_EQ(t[0].tiles(), 6);
  EXPECT_EQ(t[1].tiles(), 6);
  // Nothing fits 0.45 x 0.25.
  EXPECT_TRUE(TilingsOf(0.45, 0.25, kCarton, o).empty());
}

TEST(PlanarPatchesTest, TheLayerTopIsOnePatchOnItsPlane) {
  LayerFrame f;
  f.Render();
  const PlanarPatches p = SegmentPlanarPatches(f.image, PlanarPatchOptions{});
  ASSERT_GE(p.patches.size(), 1u);
  int layer = p.PatchAt(320, 240);
  ASSERT_GE(layer, 0);
  const PlanarPatch& top = p.patches[layer];
  EXPECT_NEAR(top.normal.z(), -1.0, 1e-3);
  EXPECT_NEAR(top.centroid.z(), kTop, 1e-3);
  const PlaneRectangle rect = OutlineRectangle(top);
  const double w = std::max(rect.width, rect.height), h = std::min(rect.width, rect.height);
  EXPECT_NEAR(w, f.width, 0.01);
  EXPECT_NEAR(h, f.height, 0.01);
}

// A layer top broken by a strip of missing returns one cell wide (as noise
// breaks a stereo camera's faces into pieces) is two regions; their fitted
// planes agree, so they are one patch again (merge_gap_cells), its outline
// the whole layer's; with merging off, two patches.
TEST(PlanarPatchesTest, PiecesOfOneFaceOnOnePlaneAreOnePatch) {
  LayerFrame f;
  f.Render();
  const CameraIntrinsics& k = f.image.camera;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 318; u < 322; ++u) {
      f.image.z[static_cast<size_t>(v) * k.width + u] = std::numeric_limits<float>::quiet_NaN();
    }
  }
  PlanarPatchOptions o;
  const PlanarPatches merged = SegmentPlanarPatches(f.image, o);
  const int left = merged.PatchAt(300, 240), right = merged.PatchAt(340, 240);
  ASSERT_GE(left, 0);
  EXPECT_EQ(left, right);
  const PlaneRectangle rect = OutlineRectangle(merged.patches[left]);
  EXPECT_NEAR(std::max(rect.width, rect.height), f.width, 0.02);
  o.merge_gap_cells = 0;
  const PlanarPatches apart = SegmentPlanarPatches(f.image, o);
  ASSERT_GE(apart.PatchAt(300, 240), 0);
  ASSERT_GE(apart.PatchAt(340, 240), 0);
  EXPECT_NE(apart.PatchAt(300, 240), apart.PatchAt(340, 240));
}

// A face w x h m, centred on the optical axis at kTop, tilted by tilt_deg
// about the camera's x axis (its normal that far from the view), on a floor
// at 1.5 m. Exact depth.
DepthImage SlantedFace(double w, double h, double tilt_deg) {
  DepthImage image;
  image.camera = CameraIntrinsics{};
  const CameraIntrinsics& k = image.camera;
  const double t = tilt_deg * M_PI / 180.0;
  const Eigen::Vector3d p0(0.0, 0.0, kTop), n(0.0, std::sin(t), -std::cos(t)),
      a = Eigen::Vector3d::UnitX(), b(0.0, std::cos(t), std::sin(t));
  image.z.assign(static_cast<size_t>(k.width) * k.height, 1.5f);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = PixelRay(k, u, v);
      const Eigen::Vector3d x = ray * (n.dot(p0) / n.dot(ray));
      if (std::abs((x - p0).dot(a)) <= w / 2 && std::abs((x - p0).dot(b)) <= h / 2) {
        image.z[static_cast<size_t>(v) * k.width + u] = static_cast<float>(x.z());
      }
    }
  }
  return image;
}

// A patch's cells each cover (z step / fx)^2 of a plane facing the camera:
// a face at 60 degrees to the view has twice the area its cells count.
TEST(PlanarPatchesTest, ASlantedFacesAreaIsMeasuredOnItsPlane) {
  for (const double tilt : {0.0, 45.0, 60.0}) {
    const DepthImage image = SlantedFace(0.40, 0.30, tilt);
    const PlanarPatches p = SegmentPlanarPatches(image, PlanarPatchOptions{});
    const int id = p.PatchAt(320, 240);
    ASSERT_GE(id, 0) << tilt;
    const PlanarPatch& face = p.patches[id];
    // The region growing leaves out about a cell along the outline.
    EXPECT_NEAR(PatchArea(face, image.camera.fx, p.step_px), 0.12, 0.015) << tilt;
    const double cell_m = face.centroid.z() / image.camera.fx * p.step_px;
    EXPECT_NEAR(face.points.size() * cell_m * cell_m, 0.12 * std::cos(tilt * M_PI / 180.0), 0.015)
        << tilt;
  }
}

// A carton's whole 0.30 x 0.20 top, tilted 64 degrees to the view (a heap's
// box on its side): its cells count less than half its outline's area, and
// counted so it was no face (generated stereo heaps: a carton's side at 48
// degrees, its rim eroded, proposed nothing). On its plane it is the top.
TEST(FaceProposalsTest, AFaceSeenObliquelyIsProposed) {
  const DepthImage image = SlantedFace(0.30, 0.20, 64.0);
  int near = 0;
  for (const Eigen::Isometry3d& pose : ProposeFromFaces(image, kCarton, {}).poses) {
    const double t = 64.0 * M_PI / 180.0;
    // The carton's centre, h / 2 behind its top's.
    const Eigen::Vector3d centre =
        Eigen::Vector3d(0.0, 0.0, kTop) - 0.075 * Eigen::Vector3d(0.0, std::sin(t), -std::cos(t));
    near += (pose.translation() - centre).norm() < 0.015;
  }
  EXPECT_GE(near, 1);
}

// Expects each pose to sit on one tile of the layer (tile centres at
// (i + 0.5) size - outline / 2 in layer coordinates), and every tile hit.
void ExpectTiles(const LayerFrame& f, const std::vector<Eigen::Isometry3d>& poses, double tile_a,
                 double tile_b) {
  const int na = static_cast<int>(std::lround(f.width / tile_a));
  const int nb = static_cast<int>(std::lround(f.height / tile_b));
  std::vector<int> hits(na * nb, 0);
  for (const Eigen::Isometry3d& pose : poses) {
    const Eigen::Vector3d c = pose.translation();
    const Eigen::Vector2d q = f.ToLayer(c.x(), c.y());
    const int i = static_cast<int>(std::floor((q.x() + f.width / 2) / tile_a));
    const int j = static_cast<int>(std::floor((q.y() + f.height / 2) / tile_b));
    ASSERT_TRUE(i >= 0 && i < na && j >= 0 && j < nb) << "pose off the layer";
    EXPECT_NEAR(q.x(), -f.width / 2 + (i + 0.5) * tile_a, 0.01);
    EXPECT_NEAR(q.y(), -f.height / 2 + (j + 0.5) * tile_b, 0.01);
    EXPECT_NEAR(c.z(), kTop + 0.075, 0.005);  // the carton's centre, h / 2 below its top
    ++hits[i * nb + j];
  }
  for (int h : hits) EXPECT_EQ(h, 1);
}

// Where proposals lie on the grid of cartons 0.2 m along the layer's a
// axis and 0.3 m along b, one of them centred on the layer's origin: the
// cells proposed (i, j: cartons from that one) and how many proposals lie
// more than 1 cm off every carton's centre.
struct GridHits {
  std::set<std::pair<int, int>> cells;
  int off_grid = 0;
  bool centre() const { return cells.count({0, 0}) > 0; }
};
GridHits OnCartonGrid(const LayerFrame& f, const std::vector<Eigen::Isometry3d>& poses) {
  GridHits h;
  for (const Eigen::Isometry3d& pose : poses) {
    const Eigen::Vector2d q = f.ToLayer(pose.translation().x(), pose.translation().y());
    const int i = static_cast<int>(std::lround(q.x() / 0.2));
    const int j = static_cast<int>(std::lround(q.y() / 0.3));
    if ((q - Eigen::Vector2d(i * 0.2, j * 0.3)).norm() > 0.01) {
      ++h.off_grid;
    } else {
      h.cells.insert({i, j});
    }
  }
  return h;
}

TEST(FaceProposalsTest, ALayerOfTouchingBoxesWithNoSeamsTilesIntoItsBoxes) {
  LayerFrame f;  // 3 x 2 cartons, no seam in depth or colour
  f.Render();
  const FaceProposals p = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  EXPECT_TRUE(p.declined.empty());
  ASSERT_EQ(p.poses.size(), 6u);
  ExpectTiles(f, p.poses, 0.30, 0.20);
}

// The detector finds the floor from the patches and passes its plane: the
// patches on it propose nothing (no poses, layer or declined tiling), the
// others as before.
TEST(FaceProposalsTest, PatchesOnTheExcludedPlaneProposeNothing) {
  LayerFrame f;  // 3 x 2 cartons at kTop on a floor at kFloor
  f.Render();
  const FaceProposals all = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  ASSERT_EQ(all.poses.size(), 6u);
  ASSERT_FALSE(all.layers.empty());
  auto plane_at = [](double z) {
    ExcludedPlane plane;
    plane.normal = -Eigen::Vector3d::UnitZ();
    plane.point = Eigen::Vector3d(0.0, 0.0, z);
    plane.max_distance_m = 0.01;
    return plane;
  };
  int calls = 0;
  const FaceProposals no_layer =
      ProposeFromFaces(f.image, kCarton, FaceProposalOptions{}, nullptr, nullptr,
                       [&](const PlanarPatches& patches) -> std::optional<ExcludedPlane> {
                         ++calls;
                         EXPECT_EQ(patches.patches.size(), all.patches.patches.size());
                         return plane_at(kTop);
                       });
  EXPECT_EQ(calls, 1);
  EXPECT_TRUE(no_layer.poses.empty());
  EXPECT_TRUE(no_layer.layers.empty());
  EXPECT_EQ(no_layer.num_patches, all.num_patches);  // found, not proposed from
  // 2 cm off the layer's plane, or tilted 15 degrees: not on it.
  for (const ExcludedPlane& beside :
       {plane_at(kTop + 0.02), [&] {
          ExcludedPlane p = plane_at(kTop);
          p.normal = Eigen::AngleAxisd(15.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()) * p.normal;
          return p;
        }()}) {
    const FaceProposals kept =
        ProposeFromFaces(f.image, kCarton, FaceProposalOptions{}, nullptr, nullptr,
                         [&](const PlanarPatches&) { return std::optional(beside); });
    EXPECT_EQ(kept.poses.size(), 6u);
  }
  const FaceProposals no_floor =
      ProposeFromFaces(f.image, kCarton, FaceProposalOptions{}, nullptr, nullptr,
                       [&](const PlanarPatches&) { return std::optional(plane_at(kFloor)); });
  ASSERT_EQ(no_floor.poses.size(), all.poses.size());
  for (size_t i = 0; i < all.poses.size(); ++i) {
    EXPECT_TRUE(no_floor.poses[i].isApprox(all.poses[i], 0.0)) << i;
  }
}

// With helpers (internal::SharedLoops, as the detector's segments thread
// helps when done), the patches are tiled on two threads: the proposals,
// layers and declined tilings are those of one thread, in the same order.
TEST(FaceProposalsTest, PatchesSharedWithAHelperProposeTheSame) {
  LayerFrame f;  // a layer and the floor around it: two patches
  f.Render();
  const FaceProposals alone = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  ASSERT_GE(alone.num_patches, 2);
  ASSERT_FALSE(alone.poses.empty());
  internal::SharedLoops loops;
  std::thread helper([&] { loops.Help(); });
  const FaceProposals shared =
      ProposeFromFaces(f.image, kCarton, FaceProposalOptions{}, nullptr, &loops);
  loops.Close();
  helper.join();
  ASSERT_EQ(shared.poses.size(), alone.poses.size());
  for (size_t i = 0; i < alone.poses.size(); ++i) {
    EXPECT_TRUE(shared.poses[i].isApprox(alone.poses[i], 0.0)) << i;
  }
  ASSERT_EQ(shared.layers.size(), alone.layers.size());
  for (size_t i = 0; i < alone.layers.size(); ++i) {
    EXPECT_EQ(shared.layers[i].patch, alone.layers[i].patch);
    EXPECT_EQ(shared.layers[i].tiles.size(), alone.layers[i].tiles.size());
  }
  EXPECT_EQ(shared.declined.size(), alone.declined.size());
}

// A rectangular top on the plane at kTop: centre, turn about the optical
// axis, half sizes. Metres, degrees.
struct Top {
  Eigen::Vector2d centre;
  double yaw_deg;
  double half_l = kCarton.l / 2, half_b = kCarton.b / 2;
  bool Contains(double x, double y, double margin = 0.0) const {
    const double c = std::cos(yaw_deg * M_PI / 180), s = std::sin(yaw_deg * M_PI / 180);
    const double dx = x - centre.x(), dy = y - centre.y();
    return std::abs(c * dx + s * dy) <= half_l + margin &&
           std::abs(-s * dx + c * dy) <= half_b + margin;
  }
};

// Exact depth of tops on one plane at kTop, each with a shadow 3 cm wide
// around it (a Kinect's: no return), the floor at kFloor beyond.
DepthImage TopsWithShadows(const std::vector<Top>& tops) {
  DepthImage image;
  const CameraIntrinsics& k = image.camera;
  image.z.assign(static_cast<size_t>(k.width) * k.height, 0.0f);
  auto any = [&](double x, double y, double margin) {
    return std::any_of(tops.begin(), tops.end(),
                       [&](const Top& t) { return t.Contains(x, y, margin); });
  };
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = PixelRay(k, u, v);
      const double x = ray.x() * kTop, y = ray.y() * kTop;
      image.z[static_cast<size_t>(v) * k.width + u] = any(x, y, 0.0) ? static_cast<float>(kTop)
                                                      : any(x, y, 0.03)
                                                          ? std::numeric_limits<float>::quiet_NaN()
                                                          : static_cast<float>(kFloor);
    }
  }
  return image;
}

// Two carton tops on one plane, 1.2 m below the camera, a shadow of a few
// pixels between them, one turned 25 degrees: merging (merge_gap_cells)
// joins them into one patch whose outline tiles as neither. The pieces
// propose each carton where it is (FaceProposalOptions::
// propose_merged_pieces); the merged patch alone proposes none of the
// turned one.
TEST(FaceProposalsTest, FacesMergedAcrossAGapAreProposedFromTheirPieces) {
  const Top tops[2] = {{{-0.17, 0.0}, 0.0}, {{0.17, 0.06}, 25.0}};
  const DepthImage image = TopsWithShadows({tops[0], tops[1]});
  const CameraIntrinsics& k = image.camera;
  FaceProposalOptions o;
  PlanarPatches pieces;
  const PlanarPatches merged = SegmentPlanarPatches(image, o.patches, &pieces);
  auto at = [&](const PlanarPatches& p, const Top& t) {
    const Eigen::Vector2d px = Project(k, Eigen::Vector3d(t.centre.x(), t.centre.y(), kTop));
    return p.PatchAt(static_cast<int>(px.x()), static_cast<int>(px.y()));
  };
  ASSERT_GE(at(merged, tops[0]), 0);
  ASSERT_EQ(at(merged, tops[0]), at(merged, tops[1])) << "the two tops are not merged";
  ASSERT_EQ(pieces.patches.size(), 2u);
  EXPECT_NE(at(pieces, tops[0]), at(pieces, tops[1]));
  EXPECT_GE(at(pieces, tops[0]), 0);
  EXPECT_GE(at(pieces, tops[1]), 0);
  // A proposal on a top: its centre within 1 cm of the carton's, its l axis
  // within 3 degrees of the top's.
  auto proposes = [&](const FaceProposals& p, const Top& t) {
    const Eigen::Vector2d axis(std::cos(t.yaw_deg * M_PI / 180), std::sin(t.yaw_deg * M_PI / 180));
    return std::any_of(p.poses.begin(), p.poses.end(), [&](const Eigen::Isometry3d& pose) {
      const Eigen::Vector3d c = pose.translation();
      const Eigen::Vector3d l = pose.linear().col(0);
      return (c.head<2>() - t.centre).norm() < 0.01 && std::abs(c.z() - (kTop + 0.075)) < 0.01 &&
             std::abs(l.head<2>().dot(axis)) > std::cos(3.0 * M_PI / 180);
    });
  };
  const FaceProposals with = ProposeFromFaces(image, kCarton, o);
  EXPECT_TRUE(proposes(with, tops[0]));
  EXPECT_TRUE(proposes(with, tops[1]));
  o.propose_merged_pieces = false;
  const FaceProposals without = ProposeFromFaces(image, kCarton, o);
  EXPECT_FALSE(proposes(without, tops[1]));
  EXPECT_LT(without.poses.size(), with.poses.size());
}

// A big flat top (0.8 x 0.6 m) and a small square (12 cm) on its plane, a
// shadow between them, as in the test above: merging joins them, and the
// piece holding nearly all of the merged patch (95 % of its cells) is not
// listed among the merged pieces (its outline, and so its faces, are the
// patch's); the small one is.
TEST(FaceProposalsTest, APieceHoldingNearlyAllOfItsMergedPatchIsNotAPiece) {
  const DepthImage image =
      TopsWithShadows({{{-0.25, 0.0}, 0.0, 0.4, 0.3}, {{0.24, 0.05}, 25.0, 0.06, 0.06}});
  const CameraIntrinsics& k = image.camera;
  PlanarPatches pieces;
  const PlanarPatches merged = SegmentPlanarPatches(image, FaceProposalOptions{}.patches, &pieces);
  auto at = [&](const PlanarPatches& p, double x, double y) {
    const Eigen::Vector2d px = Project(k, Eigen::Vector3d(x, y, kTop));
    return p.PatchAt(static_cast<int>(px.x()), static_cast<int>(px.y()));
  };
  ASSERT_GE(at(merged, -0.25, 0.0), 0);
  ASSERT_EQ(at(merged, -0.25, 0.0), at(merged, 0.24, 0.05)) << "the two are not merged";
  ASSERT_EQ(pieces.patches.size(), 1u);  // the small one alone
  EXPECT_EQ(at(pieces, -0.25, 0.0), -1);
  EXPECT_EQ(at(pieces, 0.24, 0.05), 0);
}

// A carton top whose rim the segmentation took in (here the outline is
// 4 cm short of 0.30 x 0.20, as a stereo camera's noise leaves it): no
// whole tiling fits, and the lying carton's face does not fit inside it
// (a standing carton's 0.20 x 0.15 does, in its corners), but the lying
// carton centred on the outline is proposed
// (FaceProposalOptions::min_eroded_share); not with the option off, nor
// for an outline under that share of the face.
TEST(FaceProposalsTest, AnOutlineALittleSmallerThanAFaceProposesItCentred) {
  LayerFrame f;
  f.width = 0.26;
  f.height = 0.16;
  auto lying_centred = [&](const FaceProposalOptions& o) {
    f.Render();
    int n = 0;
    for (const Eigen::Isometry3d& pose : ProposeFromFaces(f.image, kCarton, o).poses) {
      const Eigen::Vector2d q = f.ToLayer(pose.translation().x(), pose.translation().y());
      const Eigen::Vector3d l = pose.linear().col(0), h = pose.linear().col(2);
      const Eigen::Vector2d l_on_layer =
          f.ToLayer(l.x() + f.centre.x(), l.y() + f.centre.y());  // a direction
      n += q.norm() < 0.01 && std::abs(l_on_layer.x()) > 0.95 && std::abs(h.z()) > 0.95;
    }
    return n;
  };
  EXPECT_EQ(lying_centred(FaceProposalOptions{}), 1);
  FaceProposalOptions off;
  off.min_eroded_share = 0.0;
  EXPECT_EQ(lying_centred(off), 0);
  f.width = 0.18;  // under 0.65 of l
  EXPECT_EQ(lying_centred(FaceProposalOptions{}), 0);
}

// An outline of 0.29 x 0.14 m tiles as one standing carton's 0.30 x 0.15
// side; it is also 0.7 of the lying carton's 0.30 x 0.20 top across, its
// rim taken in: that top, centred on it, is proposed beside the tile
// (FaceProposalOptions::eroded_beside_tile), and not with the option off.
TEST(FaceProposalsTest, AnOutlineThatTilesProposesTheBiggerFaceItIsMostOfToo) {
  LayerFrame f;
  f.width = 0.29;
  f.height = 0.14;
  f.Render();
  auto lying_centred = [&](const FaceProposalOptions& o) {
    int n = 0;
    for (const Eigen::Isometry3d& pose : ProposeFromFaces(f.image, kCarton, o).poses) {
      const Eigen::Vector2d q = f.ToLayer(pose.translation().x(), pose.translation().y());
      const Eigen::Vector3d h = pose.linear().col(2);
      n += q.norm() < 0.01 && std::abs(h.z()) > 0.95;
    }
    return n;
  };
  FaceProposalOptions o;
  ASSERT_EQ(TilingsOf(0.29, 0.14, kCarton, o).size(), 1u);
  EXPECT_EQ(lying_centred(o), 1);
  o.eroded_beside_tile = false;
  EXPECT_EQ(lying_centred(o), 0);
}

// A carton's top within a few pixels of the image border (its patch within
// a normal window of the border) is that face whole: it proposes the face;
// a layer cut by the border proposes nothing and is no layer.
TEST(FaceProposalsTest, AFaceAtTheImageBorderProposesItButALayerThereDoesNot) {
  LayerFrame f;
  f.yaw_deg = 0.0;
  f.width = 0.30;
  f.height = 0.20;
  // Its right side 4 px inside the image (fx 525, cx 319.5, at kTop).
  const double right_edge_x = (636.0 - 319.5) / 525.0 * kTop;
  f.centre = Eigen::Vector2d(right_edge_x - 0.15, 0.0);
  f.Render();
  auto centred = [&](const FaceProposals& p) {
    int n = 0;
    for (const Eigen::Isometry3d& pose : p.poses) {
      const Eigen::Vector2d q = f.ToLayer(pose.translation().x(), pose.translation().y());
      n += q.norm() < 0.01 && std::abs(pose.linear().col(2).z()) > 0.95;
    }
    return n;
  };
  const FaceProposals at_border = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  EXPECT_GE(centred(at_border), 1);
  EXPECT_TRUE(at_border.layers.empty());
  FaceProposalOptions off;
  off.propose_at_border = false;
  EXPECT_EQ(centred(ProposeFromFaces(f.image, kCarton, off)), 0);
  // A 0.9 x 0.4 layer cut by the same border: nothing.
  f.width = 0.9;
  f.height = 0.4;
  f.centre = Eigen::Vector2d(right_edge_x - 0.3, 0.0);
  f.Render();
  const FaceProposals layer = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  EXPECT_TRUE(layer.poses.empty());
  EXPECT_TRUE(layer.layers.empty());
}

TEST(FaceProposalsTest, ANotchedLayerProposesOnlyTheTilesThatAreThere) {
  LayerFrame f;
  f.width = 0.9;
  f.height = 0.6;  // 3 x 3 cartons ...
  f.Render();
  // ... with one corner carton taken away: the floor shows there.
  const CameraIntrinsics& k = f.image.camera;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = PixelRay(k, u, v);
      const Eigen::Vector2d q = f.ToLayer(ray.x() * kTop, ray.y() * kTop);
      if (q.x() > 0.15 && q.y() > 0.1) f.image.z[static_cast<size_t>(v) * k.width + u] = kFloor;
    }
  }
  const FaceProposals p = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  EXPECT_TRUE(p.declined.empty());
  EXPECT_EQ(p.poses.size(), 8u);
}

// A layer three cartons wide whose ends run past the image's top and
// bottom: no corner of it in view, its outline no whole number of faces.
// The seams between its cartons show only as lines of missing returns (a
// structured-light camera at a 1 mm gap): split along them, it proposes
// each carton between two seams, or a seam and a side of the outline, on
// both axes; without the lines, or with the split off, nothing.
TEST(SeamSplitFacesTest, ALayerCutByTheBorderSplitsAlongLinesOfMissingReturns) {
  LayerFrame f;
  f.yaw_deg = 8.0;
  f.width = 0.6;   // three cartons' 0.20 m sides along a
  f.height = 1.6;  // past the image's top and bottom
  f.centre = Eigen::Vector2d(0.01, 0.0);
  f.Render();
  EXPECT_TRUE(ProposeFromFaces(f.image, kCarton, FaceProposalOptions{}).poses.empty());
  const CameraIntrinsics& k = f.image.camera;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = PixelRay(k, u, v);
      const Eigen::Vector2d q = f.ToLayer(ray.x() * kTop, ray.y() * kTop);
      if (std::abs(q.x()) > f.width / 2) continue;  // the floor
      bool seam = false;
      for (double a : {-0.1, 0.1}) seam |= std::abs(q.x() - a) < 0.0012;
      for (double b : {-0.45, -0.15, 0.15, 0.45}) seam |= std::abs(q.y() - b) < 0.0012;
      if (seam) f.image.z[static_cast<size_t>(v) * k.width + u] = std::nanf("");
    }
  }
  const FaceProposals split = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  // Every proposal one of the nine cartons framed by seams, its 0.30 m side
  // along the layer's b axis, and every one of them proposed.
  const Eigen::Vector3d along_b = f.FromLayer(0.0, 1.0, 0.0) - f.FromLayer(0.0, 0.0, 0.0);
  std::vector<int> seen(9, 0);
  for (const Eigen::Isometry3d& pose : split.poses) {
    const Eigen::Vector2d q = f.ToLayer(pose.translation().x(), pose.translation().y());
    const int i = static_cast<int>(std::lround(q.x() / 0.2)) + 1;
    const int j = static_cast<int>(std::lround(q.y() / 0.3)) + 1;
    ASSERT_TRUE(i >= 0 && i < 3 && j >= 0 && j < 3) << q.transpose();
    EXPECT_LT((q - Eigen::Vector2d((i - 1) * 0.2, (j - 1) * 0.3)).norm(), 0.01) << q.transpose();
    EXPECT_GT(std::abs(pose.linear().col(0).dot(along_b)), 0.99);
    EXPECT_GT(std::abs(pose.linear().col(2).z()), 0.99);
    ++seen[3 * j + i];
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 0), 0)
      << seen[0] << seen[1] << seen[2] << " " << seen[3] << seen[4] << seen[5] << " " << seen[6]
      << seen[7] << seen[8] << " patches " << split.num_patches;
  FaceProposalOptions off;
  off.seam_split.enabled = false;
  EXPECT_TRUE(ProposeFromFaces(f.image, kCarton, off).poses.empty());
}

// The layer of ALayerCutByTheBorderSplitsAlongLinesOfMissingReturns, its
// seams filled in the depth (active stereo smooths them away) and plain
// only in colour: dark lines along the whole layer, with a darker tape
// strip and a label on the cartons. Each seam is a line darker than the
// image a centimetre to either side (SeamSplitOptions::colour_seam_share);
// the tape's and the label's edges are darker on one side only. The nine
// cartons are proposed; with colour seams off, none.
TEST(SeamSplitFacesTest, SeamsOnlyTheColourShowsSplitALayerCutByTheBorder) {
  LayerFrame f;
  f.yaw_deg = 8.0;
  f.width = 0.6;
  f.height = 1.6;
  f.centre = Eigen::Vector2d(0.01, 0.0);
  f.Render();
  // Tape along the middle column's cartons (5 cm wide) and a label.
  f.Paint({-0.1, 0.1}, {-0.45, -0.15, 0.15, 0.45},
          {Eigen::Vector4d(-0.025, -0.8, 0.025, 0.8), Eigen::Vector4d(0.12, 0.02, 0.22, 0.1)});
  auto proposed = [&](double share) {
    FaceProposalOptions o;
    o.seam_split.colour_seam_share = share;
    const GridHits h = OnCartonGrid(f, ProposeFromFaces(f.image, kCarton, o).poses);
    EXPECT_EQ(h.off_grid, 0) << "proposals off every carton";
    for (const auto& [i, j] : h.cells) {
      EXPECT_TRUE(std::abs(i) <= 1 && std::abs(j) <= 1) << "a proposal off the layer " << i << j;
    }
    return static_cast<int>(h.cells.size());
  };
  EXPECT_EQ(proposed(0.5), 9);
  EXPECT_EQ(proposed(0.0), 0);
}

// A layer filling the whole view, turned 4 degrees from the image's axes:
// its patch's outline is the view's own rectangle, and lines along it cross
// every seam at 4 degrees (a line 1 m long runs 7 cm off it). Turned to
// where the holes line up (SeamSplitOptions::align_max_deg), the lines run
// along the seams again and the cartons they frame are proposed.
TEST(SeamSplitFacesTest, SeamsTurnedFromALayerOutlineCutByTheBorderAreFollowed) {
  LayerFrame f;
  f.yaw_deg = 4.0;
  f.width = 2.0;
  f.height = 2.0;
  f.centre = Eigen::Vector2d(0.0, 0.0);
  f.Render();
  const CameraIntrinsics& k = f.image.camera;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d ray = PixelRay(k, u, v);
      const Eigen::Vector2d q = f.ToLayer(ray.x() * kTop, ray.y() * kTop);
      bool seam = false;
      for (double a : {-0.5, -0.3, -0.1, 0.1, 0.3, 0.5}) seam |= std::abs(q.x() - a) < 0.0012;
      for (double b : {-0.45, -0.15, 0.15, 0.45}) seam |= std::abs(q.y() - b) < 0.0012;
      if (seam) f.image.z[static_cast<size_t>(v) * k.width + u] = std::nanf("");
    }
  }
  // The carton between the seams a = -0.1, 0.1 and b = -0.15, 0.15 (its
  // 0.30 m side along b) is proposed, and nothing off every carton.
  const GridHits turned =
      OnCartonGrid(f, ProposeFromFaces(f.image, kCarton, FaceProposalOptions{}).poses);
  EXPECT_TRUE(turned.centre());
  EXPECT_EQ(turned.off_grid, 0);
  FaceProposalOptions along_outline;
  along_outline.seam_split.align_max_deg = 0.0;
  EXPECT_FALSE(OnCartonGrid(f, ProposeFromFaces(f.image, kCarton, along_outline).poses).centre());
}

// The same, turned 30 degrees, its seams filled in the depth and plain
// only in colour (active stereo): the holes that line up are the colour
// image's thin dark lines, and the outline (the view's rectangle) is 30
// degrees off them, past a search of 8 degrees but within 45.
TEST(SeamSplitFacesTest, ColourSeamsFarOffALayerOutlineCutByTheBorderAreFollowed) {
  LayerFrame f;
  f.yaw_deg = 30.0;
  f.width = 2.4;
  f.height = 2.4;
  f.centre = Eigen::Vector2d(0.0, 0.0);
  f.Render();
  f.Paint({-0.7, -0.5, -0.3, -0.1, 0.1, 0.3, 0.5, 0.7},
          {-1.05, -0.75, -0.45, -0.15, 0.15, 0.45, 0.75, 1.05});
  auto centre_proposed = [&](double max_deg) {
    FaceProposalOptions o;
    o.seam_split.align_max_deg = max_deg;
    return OnCartonGrid(f, ProposeFromFaces(f.image, kCarton, o).poses).centre() ? 1 : 0;
  };
  EXPECT_EQ(centre_proposed(8.0), 0);
}

TEST(FaceProposalsTest, TwoTilingsOfOneOutlineAreDeclinedWithoutASeamCue) {
  LayerFrame f;
  f.width = 0.6;
  f.height = 0.6;  // 2 x 3 or 3 x 2 cartons
  f.Render();
  const FaceProposals p = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  EXPECT_TRUE(p.poses.empty());
  ASSERT_FALSE(p.declined.empty());
  EXPECT_NE(p.declined[0].reason.find("tiles two ways"), std::string::npos) << p.declined[0].reason;
}

TEST(FaceProposalsTest, ColourSeamsDecideBetweenTwoTilings) {
  LayerFrame f;
  f.width = 0.6;
  f.height = 0.6;
  f.Render();
  // Seams of 2 x 3 cartons with l along the layer's a axis: a line at a = 0
  // and lines at b = -0.1, 0.1.
  f.Paint({0.0}, {-0.1, 0.1});
  const FaceProposals p = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  EXPECT_TRUE(p.declined.empty());
  ASSERT_EQ(p.poses.size(), 6u);
  ExpectTiles(f, p.poses, 0.30, 0.20);
  // The other way round: lines at a = -0.1, 0.1 and b = 0.
  f.Paint({-0.1, 0.1}, {0.0});
  const FaceProposals q = ProposeFromFaces(f.image, kCarton, FaceProposalOptions{});
  ASSERT_EQ(q.poses.size(), 6u);
  ExpectTiles(f, q.poses, 0.20, 0.30);
}

// A row of cartons, 0.6 x 0.2 m, rendered.
LayerFrame OneRow() {
  LayerFrame f;
  f.width = 0.6;
  f.height = 0.2;
  f.Render();
  return f;
}

// The line along a = 0 across the whole layer, from b = -h/2 to h/2.
SeamCue CueAtMiddle(const LayerFrame& f) {
  return ColourSeamAlong(f.image, f.FromLayer(0.0, -f.height / 2, kTop),
                         f.FromLayer(0.0, f.height / 2, kTop),
                         f.FromLayer(1.0, 0.0, 0.0) - f.FromLayer(0.0, 0.0, 0.0), SeamCueOptions{});
}

TEST(ColourSeamTest, ARealSeamRunningTheWholeSideIsASeam) {
  LayerFrame f = OneRow();
  f.Paint({0.0}, {});
  const SeamCue cue = CueAtMiddle(f);
  EXPECT_TRUE(cue.seam);
  EXPECT_GT(cue.coverage, 0.9);
  EXPECT_NEAR(cue.offset_m, 0.0, 0.003);
}

// Packing tape along the middle of the flaps: a 5 cm strip whose edges are
// steps of shade running the whole face. A step is not a seam (by default);
// the dark line where two boxes meet is.
TEST(ColourSeamTest, TheEdgeOfATapeStripIsNotASeam) {
  LayerFrame f = OneRow();
  // A darker strip from a = 0 to a = 0.05 over the whole height: its edge
  // lies on the line a = 0.
  f.Paint({}, {}, {Eigen::Vector4d(0.0, -0.1, 0.05, 0.1)});
  EXPECT_FALSE(CueAtMiddle(f).seam) << "coverage " << CueAtMiddle(f).coverage;
  SeamCueOptions steps;
  steps.accept_steps = true;
  const SeamCue with_steps = ColourSeamAlong(
      f.image, f.FromLayer(0.0, -f.height / 2, kTop), f.FromLayer(0.0, f.height / 2, kTop),
      f.FromLayer(1.0, 0.0, 0.0) - f.FromLayer(0.0, 0.0, 0.0), steps);
  EXPECT_TRUE(with_steps.seam) << "coverage " << with_steps.coverage;
}

TEST(ColourSeamTest, ALabelAcrossTheLineDoesNotMakeASeam) {
  LayerFrame f = OneRow();
  // A dark label 8 x 6 cm straddling a = 0 (its edges cross the line), and
  // a barcode-like block whose edge lies on the line over a third of it.
  f.Paint({}, {},
          {Eigen::Vector4d(-0.04, -0.08, 0.04, -0.02), Eigen::Vector4d(0.0, 0.02, 0.06, 0.085)});
  const SeamCue cue = CueAtMiddle(f);
  EXPECT_FALSE(cue.seam) << "coverage " << cue.coverage;
  // Plain cardboard: nothing.
  f.Paint({}, {});
  EXPECT_FALSE(CueAtMiddle(f).seam);
  // No colour at all: never a seam.
  f.image.grey.clear();
  EXPECT_FALSE(CueAtMiddle(f).seam);
}

// A seam only a few grey levels darker than grainy cardboard (a stereo
// camera's colour of bricks or cartons at 2 m): no sample shows it plainly,
// the side's mean does.
TEST(ColourSeamTest, AFaintSeamOnGrainyCardboardIsASeam) {
  LayerFrame f = OneRow();
  f.grain = 5.0;
  f.seam_grey = 150.0f - 7.0f;
  f.Paint({0.0}, {});
  const SeamCue cue = CueAtMiddle(f);
  EXPECT_TRUE(cue.seam) << "coverage " << cue.coverage;
  EXPECT_NEAR(cue.offset_m, 0.0, 0.004);
  // Plain lines only: missed.
  SeamCueOptions plain;
  plain.min_line_contrast = 0.0;
  EXPECT_FALSE(ColourSeamAlong(f.image, f.FromLayer(0.0, -f.height / 2, kTop),
                               f.FromLayer(0.0, f.height / 2, kTop),
                               f.FromLayer(1.0, 0.0, 0.0) - f.FromLayer(0.0, 0.0, 0.0), plain)
                   .seam);
  // The grain alone makes none.
  f.Paint({}, {});
  EXPECT_FALSE(CueAtMiddle(f).seam) << "coverage " << CueAtMiddle(f).coverage;
}

// A seam's turn against the side: where each half of the side has it.
TEST(ColourSeamTest, ASlantedSeamGivesItsSlope) {
  LayerFrame f;
  f.width = 0.6;
  f.height = 0.4;
  f.Render();
  for (double slope : {0.0, 0.02, -0.02}) {
    f.seam_slope = slope;
    f.Paint({0.0}, {});
    const SeamCue cue = CueAtMiddle(f);
    ASSERT_TRUE(cue.seam) << slope;
    ASSERT_TRUE(cue.slope.has_value()) << slope;
    EXPECT_NEAR(*cue.slope, slope, 0.01) << slope;
  }
  // A faint one too.
  f.grain = 4.0;
  f.seam_grey = 150.0f - 8.0f;
  f.seam_slope = 0.01;
  f.Paint({0.0}, {});
  const SeamCue faint = CueAtMiddle(f);
  ASSERT_TRUE(faint.seam) << "coverage " << faint.coverage;
  ASSERT_TRUE(faint.slope.has_value());
  EXPECT_NEAR(*faint.slope, 0.01, 0.01);
}

// Degenerate sides: wholly outside the image, of zero length, or behind the
// camera give no seam (and no slope), whatever the options.
TEST(ColourSeamTest, DegenerateSidesAreNoSeam) {
  LayerFrame f;
  f.Render();
  f.grain = 5.0;
  f.Paint({0.0}, {});
  const Eigen::Vector3d across(1.0, 0.0, 0.0);
  for (const SeamCueOptions& o : {SeamCueOptions{}, [] {
                                    SeamCueOptions t;
                                    t.texture_px = 0.0;
                                    t.search_px = 0.0;
                                    return t;
                                  }()}) {
    const SeamCue outside = ColourSeamAlong(f.image, Eigen::Vector3d(5.0, 5.0, 1.2),
                                            Eigen::Vector3d(5.0, 5.3, 1.2), across, o);
    EXPECT_FALSE(outside.seam);
    EXPECT_FALSE(outside.slope.has_value());
    const Eigen::Vector3d p = f.FromLayer(0.0, 0.0, kTop);
    const SeamCue point = ColourSeamAlong(f.image, p, p, across, o);
    EXPECT_FALSE(point.slope.has_value());
    EXPECT_FALSE(ColourSeamAlong(f.image, -p, p, across, o).seam);
  }
}

// Wood grain (a pallet's deck boards): faint lines every few pixels, one of
// them on the side. A faint line that does not stand out from the lines
// parallel to it is texture, not a seam.
TEST(ColourSeamTest, WoodGrainStripesAreNoSeam) {
  LayerFrame f = OneRow();
  f.grain = 3.0;
  f.stripe_period_m = 0.011;  // ~5 px at 1.2 m
  f.stripe_dark = 9.0f;
  f.Paint({}, {});
  EXPECT_FALSE(CueAtMiddle(f).seam) << "coverage " << CueAtMiddle(f).coverage;
  SeamCueOptions no_texture_check;
  no_texture_check.texture_ratio = 0.0;
  EXPECT_TRUE(ColourSeamAlong(f.image, f.FromLayer(0.0, -f.height / 2, kTop),
                              f.FromLayer(0.0, f.height / 2, kTop),
                              f.FromLayer(1.0, 0.0, 0.0) - f.FromLayer(0.0, 0.0, 0.0),
                              no_texture_check)
                  .seam);
}

// The layer a face lies on and its tiles: a tile is one, a box turned
// across the layer (a strip cut off by a false seam, as a Kinect frame of a
// touching column showed in the simulated cell) or shifted by half a box is
// none; a face on the floor is on no layer.
TEST(LayerCheckTest, TheLayerUnderAFaceAndItsTiles) {
  LayerFrame f;  // 3 x 2 cartons, no seam
  f.Render();
  FaceProposalOptions o;
  const FaceProposals p = ProposeFromFaces(f.image, kCarton, o);
  ASSERT_EQ(p.layers.size(), 1u);
  ASSERT_EQ(p.layers[0].tiles.size(), 6u);
  EXPECT_GT(p.layers[0].fill, 0.9);
  const LayerTiles& layer = p.layers[0];
  const Eigen::Vector3d up(0, 0, -1);  // the faces look at the camera
  auto face_centre = [](const Eigen::Isometry3d& box) {
    return Eigen::Vector3d(box.translation() - Eigen::Vector3d(0, 0, 0.075));
  };
  for (const Eigen::Isometry3d& tile : p.poses) {
    EXPECT_EQ(LayerUnder(p, f.image, face_centre(tile), up, o), 0);
    EXPECT_TRUE(IsLayerTile(layer, kCarton, tile, o));
  }
  // Turned by 90 degrees about the normal, anchored on the layer's corner.
  const Eigen::Isometry3d& first = p.poses.front();
  Eigen::Isometry3d turned = first;
  turned.linear() = first.linear() * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  turned.translation() += first.linear() * Eigen::Vector3d(-0.05, 0.05, 0.0);
  EXPECT_EQ(LayerUnder(p, f.image, face_centre(turned), up, o), 0);
  EXPECT_FALSE(IsLayerTile(layer, kCarton, turned, o));
  // Shifted by half a box along its length.
  Eigen::Isometry3d shifted = first;
  shifted.translation() += first.linear() * Eigen::Vector3d(0.15, 0.0, 0.0);
  EXPECT_FALSE(IsLayerTile(layer, kCarton, shifted, o));
  // A face on the floor is on no layer.
  EXPECT_EQ(LayerUnder(p, f.image, Eigen::Vector3d(0.6, 0.4, kFloor), up, o), -1);
  // A patch filling less than layer_min_fill of its outline is no layer.
  o.layer_min_fill = std::min(1.0, layer.fill + 0.05);
  if (layer.fill < o.layer_min_fill) {
    EXPECT_EQ(LayerUnder(p, f.image, face_centre(first), up, o), -1);
  }
}

TEST(FaceProposalOptionsTest, ValidateNamesTheField) {
  FaceProposalOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.size_tolerance_m = -1;
  EXPECT_NE(o.Validate().message().find("size_tolerance_m=-1"), std::string::npos);
  o = {};
  o.seams.min_coverage = 2;
  EXPECT_NE(o.Validate().message().find("min_coverage=2"), std::string::npos);
  o = {};
  o.seams.texture_ratio = -1;
  EXPECT_NE(o.Validate().message().find("texture_ratio=-1"), std::string::npos);
  o = {};
  o.patches.step_px = 0;
  EXPECT_NE(o.Validate().message().find("step_px=0"), std::string::npos);
  o = {};
  o.layer_match_m = 0;
  EXPECT_NE(o.Validate().message().find("layer_match_m=0"), std::string::npos);
  o = {};
  o.min_eroded_share = 1.5;
  EXPECT_NE(o.Validate().message().find("min_eroded_share=1.5"), std::string::npos);
  o = {};
  o.seam_split.min_seam_share = 0;
  EXPECT_NE(o.Validate().message().find("seam_split.min_seam_share=0"), std::string::npos);
  o = {};
  o.seam_split.max_side_m = -2;
  EXPECT_NE(o.Validate().message().find("seam_split.max_side_m=-2"), std::string::npos);
  o = {};
  o.seam_split.align_max_deg = 60;
  EXPECT_NE(o.Validate().message().find("seam_split.align_max_deg=60"), std::string::npos);
  o = {};
  o.seam_split.align_step_deg = 0;
  EXPECT_NE(o.Validate().message().find("seam_split.align_step_deg=0"), std::string::npos);
  o = {};
  o.seam_split.colour_seam_share = 2;
  EXPECT_NE(o.Validate().message().find("seam_split.colour_seam_share=2"), std::string::npos);
  o = {};
  o.seam_split.colour_flank_m = 0;
  EXPECT_NE(o.Validate().message().find("seam_split.colour_flank_m=0"), std::string::npos);
  o = {};
  o.seam_split.colour_min_contrast = -1;
  EXPECT_NE(o.Validate().message().find("seam_split.colour_min_contrast=-1"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose
