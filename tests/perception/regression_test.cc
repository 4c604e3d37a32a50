// Regression tests: each one reproduces a detector bug found while the
// stage tests were written (and failed before its fix). The comments say
// what the bug was.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/perception/box_refinement.h"
#include "common/perception/camera_model.h"
#include "common/perception/detector.h"
#include "common/perception/edge_segments.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"
#include "tests/support/scene_kinds.h"
#include "tests/support/sensor_options.h"

namespace cornerpose::testing {
namespace {

// The error of `box` against the ground-truth box nearest to it (by
// translation), symmetries handled.
PoseError AgainstNearest(const DetectedBox& box, const std::vector<GroundTruthBox>& truth) {
  PoseError nearest{1e9, 1e9};
  for (const GroundTruthBox& gt : truth) {
    const PoseError e = ComparePoses(box.camera_T_box, gt.camera_T_box, gt.dims);
    if (e.translation_m < nearest.translation_m) nearest = e;
  }
  return nearest;
}

// Returned boxes 2 cm or 10 degrees or more from every box of the frame.
int WrongBoxes(const Detection& det, const RenderedScene& r) {
  int wrong = 0;
  for (const DetectedBox& b : det.boxes) {
    const PoseError nearest = AgainstNearest(b, r.boxes);
    wrong += nearest.translation_m > 0.02 || nearest.rotation_deg > 10.0;
  }
  return wrong;
}

// The frame's detections with a rule off and on ({off, on}; `set_rule`
// sets it in the options), each checked for wrong boxes: none with the rule
// on, and none with it off too unless `wrong_without` (a rule that takes a
// wrong box out: then at least one).
std::array<Detection, 2> DetectedWithRuleOffAndOn(
    const PointCloud& cloud, const RenderedScene& r, const BoxDims& dims,
    const std::function<void(bool on, DetectorOptions*)>& set_rule, bool wrong_without = false) {
  std::array<Detection, 2> out;
  for (const bool on : {false, true}) {
    DetectorOptions options;
    options.box = dims;
    set_rule(on, &options);
    absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    EXPECT_TRUE(det.ok()) << det.status();
    if (!det.ok()) continue;
    if (on || !wrong_without) {
      EXPECT_EQ(WrongBoxes(*det, r), 0) << (on ? "rule on" : "rule off");
    } else {
      EXPECT_GE(WrongBoxes(*det, r), 1) << "without the rule the wrong box is returned";
    }
    out[on] = *std::move(det);
  }
  return out;
}

// The frame's detection with the default options: none of its boxes wrong
// (rules pinned as they were made, with options since changed, are checked
// against the defaults too). Returns the boxes.
size_t DefaultsReturnNoWrongBox(const PointCloud& cloud, const RenderedScene& r,
                                const BoxDims& dims) {
  DetectorOptions options;
  options.box = dims;
  const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
  EXPECT_TRUE(det.ok()) << det.status();
  if (!det.ok()) return 0;
  EXPECT_EQ(WrongBoxes(*det, r), 0) << "with the default options";
  return det->boxes.size();
}

// Frame `i` of one of scripts/evaluate's generated Kinect sets
// (make_frames --sensor kinect --kind KIND --seed S renders frame i with
// seed 1000 S + i), as the generator renders it.
absl::StatusOr<RenderedScene> SensorFrame(SensorKind sensor, bool color, const std::string& kind,
                                          const BoxDims& dims, int i, uint32_t seed) {
  const CameraIntrinsics k = *SensorIntrinsics(sensor);
  std::string type;
  const absl::StatusOr<Scene> scene =
      MakeSceneOfKind(kind, dims, i, seed, SensorPlacement(sensor, k), &type);
  if (!scene.ok()) return scene.status();
  SensorOptions options;
  options.kind = sensor;
  options.color.enabled = color;
  return Render(*scene, options);
}

absl::StatusOr<RenderedScene> KinectFrame(const std::string& kind, const BoxDims& dims, int i,
                                          uint32_t seed) {
  return SensorFrame(SensorKind::kKinect, false, kind, dims, i, seed);
}

// The frame's cloud with its depth rounded to millimetres, as the PNGs of
// scripts/evaluate's sets hold it.
PointCloud RoundedToMillimetres(const RenderedScene& r) {
  PointCloud cloud = r.cloud;
  for (int v = 0; v < cloud.height; ++v) {
    for (int u = 0; u < cloud.width; ++u) {
      Eigen::Vector3f& p = cloud.xyz[static_cast<size_t>(v) * cloud.width + u];
      if (!PointCloud::IsValid(p)) continue;
      const double z = std::round(p.z() * 1000.0) / 1000.0;
      p = (z * PixelRay(r.camera, u, v)).cast<float>();
    }
  }
  return cloud;
}

// Was: FindExtremities (common/perception/edge_segments.cc, the
// `d1.dot(d2) < 0.0f` test) decides "all neighbours lie on the reference's
// side" with full 3-D vectors. A point of a band that sits beside the
// reference, across the line, has d1 almost perpendicular to the line, and
// every neighbour along the line then lies on the reference's side of it:
// it is taken as an extremity, e1 lands next to the reference and the
// segment is cut in the middle of a dense run. The side test should use the
// position along the run's axis (sign of (t_ref - t_i) * (t_j - t_i)).
TEST(RegressionTest, FindExtremitiesIgnoresAPointBesideTheReference) {
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i <= 100; ++i) pts.emplace_back(0.002f * i, 0.0f, 1.0f);  // x in [0, 0.2]
  const int reference = 50;                                                 // x = 0.1
  pts.emplace_back(0.1f, 0.004f, 1.0f);  // 4 mm beside the reference, across the line
  const auto [e1, e2] = FindExtremities(pts, reference, 0.02);
  // Expected: the two ends of the run, x = 0 and x = 0.2.
  // Actual: e1 is the point beside the reference (index 101), e2 the reference.
  const float lo = std::min(pts[e1].x(), pts[e2].x());
  const float hi = std::max(pts[e1].x(), pts[e2].x());
  EXPECT_NEAR(lo, 0.0f, 1e-4f);
  EXPECT_NEAR(hi, 0.2f, 1e-4f);
}

// The same bug on data like the detector's: the sides of a rectangle drawn
// as 2 mm (1 sigma) noisy bands. About one seed in four splits a side into
// two segments although the band has no gap (seeds 1, 4, 6, 8, 11, ... of
// 100). Seed 1: the 0.30 m side from (0.16, 0.12, 1.25) splits at (0.00,
// 0.06, 1.25) into 0.167 m + 0.119 m.
TEST(RegressionTest, NoisyRectangleSidesAreNotSplit) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d c(0.05, -0.02, 1.2);
  const std::array<Eigen::Vector3d, 4> corners = {
      c + R * Eigen::Vector3d(-0.15, -0.10, 0), c + R * Eigen::Vector3d(0.15, -0.10, 0),
      c + R * Eigen::Vector3d(0.15, 0.10, 0), c + R * Eigen::Vector3d(-0.15, 0.10, 0)};
  for (uint32_t seed : {1u, 4u, 6u, 8u, 11u}) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d& a = corners[k];
      const Eigen::Vector3d& b = corners[(k + 1) % 4];
      const Eigen::Vector3d d = (b - a).normalized();
      const Eigen::Vector3d u = d.unitOrthogonal(), v = d.cross(u);
      std::uniform_real_distribution<double> along(0.0, (b - a).norm());
      std::normal_distribution<double> across(0.0, 0.002);
      const int n = static_cast<int>(1500 * (b - a).norm());
      for (int i = 0; i < n; ++i) {
        pts.push_back((a + along(rng) * d + across(rng) * u + across(rng) * v).cast<float>());
      }
    }
    std::shuffle(pts.begin(), pts.end(), rng);
    const auto segments = FitEdgeSegments(pts, EdgeSegmentOptions{});
    ASSERT_TRUE(segments.ok());
    EXPECT_EQ(segments->size(), 4u) << "seed " << seed;
  }
}

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};

// Was: DetectBoxes returns wrong boxes with high scores. The hypothesis is a
// box stood on end (l vertical) whose b x h face covers half of a real top
// face, its lower half sunk into the floor. Nothing contradicts it: the
// sunk part is hidden behind the floor and counts as "occluded", not
// "seen through" (box_evidence.cc has no notion of the floor), and the side
// of its grasp face that lies in the middle of the real top face, where the
// face runs on flat, is taken for a seam (see the next test). The true box,
// scored lower, is then dropped as overlapping the wrong one (with
// acceptance.overlap_margin_m = 0.2 both come out: the true one scores
// 0.921, the wrong one 0.922). As of commit fcd3206: isolated carton_s seed
// 2 (105.5 mm / 89.9 deg off, 150 mm into the floor, score 0.92, grasp face
// +x, sides free/free/seam/free), isolated brick seeds 4 and 15 (~85 mm /
// 118 deg, 134 mm into the floor) and carton_s heaps (10 boxes) seeds 11
// and 12; versions of the detector an hour apart showed it on other seeds
// (brick 1, 6 and 20, heap 7). tests/perception/detector_test.cc counts these boxes
// apart (kSunkBelowFloorM).
TEST(RegressionTest, NoWrongBoxOnIsolatedAndHeapScenes) {
  struct Case {
    bool heap;
    BoxDims dims;
    uint32_t seed;
  };
  const BoxDims brick{0.19, 0.09, 0.057};
  for (const Case& c : {Case{false, kCartonS, 2}, Case{false, brick, 4}, Case{false, brick, 15},
                        Case{true, kCartonS, 11}, Case{true, kCartonS, 12}}) {
    const Scene scene =
        c.heap ? MakeHeapScene(c.dims, 10, c.seed) : MakeIsolatedScene(c.dims, 3, c.seed);
    const RenderedScene out = Render(scene, NoiseOptions{});
    DetectorOptions options;
    options.box = c.dims;
    const absl::StatusOr<Detection> det = DetectBoxes(out.cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    for (const DetectedBox& box : det->boxes) {
      const PoseError nearest = AgainstNearest(box, out.boxes);
      const double nearest_m = nearest.translation_m, nearest_deg = nearest.rotation_deg;
      EXPECT_LT(nearest_m, 0.02) << (c.heap ? "heap" : "isolated") << " l=" << c.dims.l << " seed "
                                 << c.seed << ": box off by " << nearest_deg << " deg, score "
                                 << box.score << (box.from_face ? " (face proposal)" : " (corner)");
    }
  }
}

// Was: a flat plane twice a box's face in each direction (a laptop lid, a
// table top, a block of the box's height) tiled into 2 x 2 boxes by the
// layer rule, with no seam anywhere. A side with no cue in depth or colour
// on a face with no seam is declined.
TEST(RegressionTest, AnUnbrokenFlatPlaneIsNotTiledIntoBoxes) {
  const BoxDims block{0.60, 0.40, 0.15};  // 2 x 2 carton_s tops, no seams
  for (uint32_t seed : {1u, 2u, 3u}) {
    const RenderedScene out = Render(MakeIsolatedScene(block, 1, seed), NoiseOptions{});
    DetectorOptions options;
    options.box = kCartonS;
    const absl::StatusOr<Detection> det = DetectBoxes(out.cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    EXPECT_TRUE(det->boxes.empty()) << "seed " << seed << ": " << det->boxes.size() << " boxes";
  }
}

// Was: RefineOnGraspFace (box_refinement.cc, FindSeam called from
// MeasureSide) reports a seam in the middle of a flat, noise-free face.
// Isolated carton_s seed 2 rendered without noise; the hypothesis of the
// previous test built from ground-truth box 0: its +x face is the -x half
// of the real top face. The side of that face at the top's middle line,
// where the real face runs on flat and unbroken, comes out kSeam (with the
// Kinect noise of the default render it comes out kContinues, as it
// should). Half the hypotheses built the same way on seeds 1-20 come out
// kContinues or kTiled; this one is a seam.
TEST(RegressionTest, NoSeamInTheMiddleOfANoiseFreeFlatFace) {
  NoiseOptions noise;
  noise.enabled = false;
  const RenderedScene out = Render(MakeIsolatedScene(kCartonS, 3, 2), noise);
  const DepthImage depth = MakeDepthImage(out.cloud, out.camera);
  // Box x along the true z (up), box z along the true -x; centre on the
  // floor under the middle of the -x half of the top.
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d::UnitZ();
  R.col(2) = -Eigen::Vector3d::UnitX();
  R.col(1) = R.col(2).cross(R.col(0));
  Eigen::Isometry3d true_T_hyp = Eigen::Isometry3d::Identity();
  true_T_hyp.linear() = R;
  true_T_hyp.translation() = Eigen::Vector3d(-0.075, 0.0, -0.075);
  Eigen::Isometry3d pose = out.boxes.at(0).camera_T_box * true_T_hyp;
  const RefinementResult r =
      RefineOnGraspFace(depth, kCartonS, BoxFace::kPlusX, RefinementOptions{}, &pose);
  // sides: +a, -a, +b, -b; -b lies on the middle line of the real top face.
  EXPECT_NE(r.sides[3], SideKind::kSeam);
}

// A seam shows along the whole side: a line of missing returns down the
// middle of a flat top (noise-free render), on half the side only, is the
// kind of dip a cluster of Kinect speckle holes makes; it was a seam (a
// box-wide strip cut out of the face), and is not with the halves rule
// (RefinementOptions::seam_halves_min_strength). The same line along the
// whole side is a seam either way.
TEST(RegressionTest, AHoleLineOnHalfASideIsNoSeam) {
  NoiseOptions noise;
  noise.enabled = false;
  const RenderedScene out = Render(MakeIsolatedScene(kCartonS, 3, 2), noise);
  const Eigen::Isometry3d camera_T_true = out.boxes.at(0).camera_T_box;
  // Missing returns on the top's middle line x = 0 (2 mm either side), for
  // y in [y0, y1) of the true box.
  auto with_holes = [&](double y0, double y1) {
    PointCloud cloud = out.cloud;
    for (Eigen::Vector3f& p : cloud.xyz) {
      if (!PointCloud::IsValid(p)) continue;
      const Eigen::Vector3d q = camera_T_true.inverse() * p.cast<double>();
      if (std::abs(q.z() - 0.075) < 0.005 && std::abs(q.x()) < 0.002 && q.y() >= y0 && q.y() < y1) {
        p = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
      }
    }
    return MakeDepthImage(cloud, out.camera);
  };
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d::UnitZ();
  R.col(2) = -Eigen::Vector3d::UnitX();
  R.col(1) = R.col(2).cross(R.col(0));
  Eigen::Isometry3d true_T_hyp = Eigen::Isometry3d::Identity();
  true_T_hyp.linear() = R;
  true_T_hyp.translation() = Eigen::Vector3d(-0.075, 0.0, -0.075);
  auto minus_b = [&](const DepthImage& depth, double halves) {
    RefinementOptions options;
    options.seam_halves_min_strength = halves;
    Eigen::Isometry3d pose = camera_T_true * true_T_hyp;
    return RefineOnGraspFace(depth, kCartonS, BoxFace::kPlusX, options, &pose).sides[3];
  };
  const DepthImage half_line = with_holes(0.0, 1.0);
  EXPECT_EQ(minus_b(half_line, -1.0), SideKind::kSeam);  // without the rule
  EXPECT_NE(minus_b(half_line, RefinementOptions{}.seam_halves_min_strength), SideKind::kSeam);
  const DepthImage whole_line = with_holes(-1.0, 1.0);
  EXPECT_EQ(minus_b(whole_line, RefinementOptions{}.seam_halves_min_strength), SideKind::kSeam);
}

// Was: one point with a finite z but a NaN or infinite x or y (or a wild
// finite one, x = 1e30) makes DetectBoxes return OK with no boxes at all.
// PointCloud::IsValid (types.h) checks z only; EstimateIntrinsics
// (camera_model.cc) sums x/z and y/z over valid pixels on a grid (every 3rd
// pixel for 640 x 480), so one such pixel on the grid makes the sums NaN
// (or the plain least squares wrong) and it fails; DetectBoxes (detector.cc)
// treats that as "too few valid points" and returns an empty Detection.
// Pixel (300, 300) is on the grid; isolated carton_s seed 1 has 3 boxes.
TEST(RegressionTest, OneBadCoordinateDoesNotHideEveryBox) {
  const RenderedScene out = Render(MakeIsolatedScene(kCartonS, 3, 1), NoiseOptions{});
  DetectorOptions options;
  options.box = kCartonS;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int what = 0; what < 3; ++what) {
    PointCloud cloud = out.cloud;
    Eigen::Vector3f& p = cloud.xyz[300 * 640 + 300];
    ASSERT_TRUE(PointCloud::IsValid(p));
    if (what == 0) p.x() = nan;
    if (what == 1) p.y() = std::numeric_limits<float>::infinity();
    if (what == 2) p.x() = 1e30f;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok());
    EXPECT_EQ(det->boxes.size(), 3u) << "case " << what;
  }
}

// Was: a carton on the lower layer of a two-height pallet, its face partly
// under a carton of the upper layer that stands right at the visible
// part's edge (no shadow between them), came back turned by 90 degrees: the
// visible strip measured a box's size, and the side against the upper
// carton counted as free, since ShadowedByOccluder (box_refinement.cc)
// took a surface above the face for an occluder only after a run of
// missing returns (more than 12 mm out). Right at the side (past the
// face's own blur), a surface in front of the face on two of three lines
// is a box standing over it: the side is occluded, and the hidden-side
// rule declines the reading. (The first fix asked for a surface a whole
// box dimension above; the upper carton's wall, seen lower, slipped past
// it once seams finer than a pixel were read in the lower layer.) The frames of
// scripts/evaluate's kinect_carton_l_s4 set (make_frames --kind depal
// --seed 4, frames 3 and 7), depth rounded to millimetres as the PNGs hold
// it.
TEST(RegressionTest, NoTurnedBoxOnALowerLayerUnderAnUpperOne) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  for (const int i : {3, 7}) {
    const absl::StatusOr<RenderedScene> frame = KinectFrame("touching2", carton_l, i, 4000 + i);
    ASSERT_TRUE(frame.ok()) << frame.status();
    const RenderedScene& r = *frame;
    const PointCloud cloud = RoundedToMillimetres(r);
    DetectorOptions options;
    options.box = carton_l;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    EXPECT_FALSE(det->boxes.empty()) << "frame " << i;
    for (const DetectedBox& b : det->boxes) {
      const PoseError nearest = AgainstNearest(b, r.boxes);
      EXPECT_LT(nearest.translation_m, 0.02)
          << "frame " << i << ": a box 2 cm or more from every carton";
      EXPECT_LT(nearest.rotation_deg, 10.0)
          << "frame " << i << ": a box turned against the nearest carton";
    }
  }
}

// Whether a returned box's grasp face reaches out of the image (within 3 px
// of its border).
bool CutByBorder(const RenderedScene& r, const BoxDims& dims, const DetectedBox& b) {
  const CameraIntrinsics& k = r.camera;
  const int f = static_cast<int>(b.grasp_face), n = f / 2, a = (n + 1) % 3, c = (n + 2) % 3;
  for (double sa : {-0.5, 0.5}) {
    for (double sc : {-0.5, 0.5}) {
      Eigen::Vector3d local = Eigen::Vector3d::Zero();
      local[n] = (f % 2 == 0 ? 0.5 : -0.5) * dims[n];
      local[a] = sa * dims[a];
      local[c] = sc * dims[c];
      const Eigen::Vector2d px = Project(k, b.camera_T_box * local);
      if (px.x() < 3 || px.y() < 3 || px.x() > k.width - 4 || px.y() > k.height - 4) return true;
    }
  }
  return false;
}

// Was: in a heap of large cartons that runs out of the frame, a carton
// whose top face has a corner out of view was declined ("grasp face cut by
// the image border") though all four of its sides were measured (a seam
// and three free borders). Such a face is pinned down: now returned where
// it is (AcceptanceOptions::measured_face_may_leave_view), and only with
// the rule off declined. scripts/evaluate's kinect_carton_l_s4 set, frame 1.
TEST(RegressionTest, ACartonWithACornerOutOfViewIsFoundWhenEverySideIsMeasured) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("heap", carton_l, 1, 4001);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  for (const bool rule : {true, false}) {
    DetectorOptions options;
    options.box = carton_l;
    options.acceptance.measured_face_may_leave_view = rule;
    // A corner just past the border is judged as in view since session 30
    // (max_out_of_view_share): off, to test this rule on its own.
    options.acceptance.max_out_of_view_share = 0.0;
    const absl::StatusOr<Detection> det = DetectBoxes(r.cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    int cut = 0;
    for (const DetectedBox& b : det->boxes) {
      const PoseError nearest = AgainstNearest(b, r.boxes);
      EXPECT_LT(nearest.translation_m, 0.01) << "rule " << rule;
      EXPECT_LT(nearest.rotation_deg, 3.0) << "rule " << rule;
      cut += CutByBorder(r, carton_l, b);
    }
    if (rule) {
      EXPECT_GE(cut, 1) << "no box with a corner out of view returned";
    } else {
      EXPECT_EQ(cut, 0);
    }
  }
}

// Was: in a Kinect pallet layer of touching cartons, a carton at the bottom
// of the image (one corner 3 px out of view) measured free on both sides
// of one axis and by seams on both of the other was declined "grasp face
// cut by the image border": the rule asked for a free side on each axis,
// from before seams gave a face its turn (the fourteenth round). Now one
// free side and every side ended is enough
// (AcceptanceOptions::leaving_view_free_axes 1); with 2 it is declined
// again. scripts/evaluate's kinect_carton_s_s20 set, frame 2.
TEST(RegressionTest, APalletCartonCutByTheBorderAndPinnedBySeamsIsFound) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("touching1", carton_s, 2, 20002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  for (const int free_axes : {1, 2}) {
    DetectorOptions options;
    options.box = carton_s;
    options.acceptance.leaving_view_free_axes = free_axes;
    options.acceptance.max_out_of_view_share = 0.0;  // this rule on its own
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    int cut = 0;
    for (const DetectedBox& b : det->boxes) {
      const PoseError nearest = AgainstNearest(b, r.boxes);
      EXPECT_LT(nearest.translation_m, 0.02) << "free axes " << free_axes;
      EXPECT_LT(nearest.rotation_deg, 10.0) << "free axes " << free_axes;
      cut += CutByBorder(r, carton_s, b);
    }
    if (free_axes == 1) {
      EXPECT_GE(cut, 1) << "no carton with a corner out of view returned";
    } else {
      EXPECT_EQ(cut, 0);
    }
  }
}

// Was: in a Kinect heap of cartons, a carton a third under the others
// (31 % of its rendered pixels hidden, its top face seen whole) was
// declined as "sunk into a surface" by a cap of 30 %; boxes pushed through
// a surface hide far more, and the floor and layer checks catch the rest.
// Now returned at the cap of 40 % (AcceptanceOptions::max_occluded), and
// declined again at 30 %. scripts/evaluate's kinect_carton_s_s3 set, frame 5.
TEST(RegressionTest, AHeapCartonAThirdUnderOthersIsNotTakenForSunk) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("heap", carton_s, 5, 3005);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  ASSERT_GE(r.boxes.size(), 9u);
  const GroundTruthBox& under = r.boxes[8];  // id 9
  auto found = [&](double cap) {
    DetectorOptions options;
    options.box = carton_s;
    options.acceptance.max_occluded = cap;
    // Session 29's groove rule (RefinementOptions::seam_depth_per_rms) off:
    // the frame as this rule was made on it (the groove rule alone changes
    // its boxes).
    options.refinement.seam_depth_per_rms = 0.0;
    const absl::StatusOr<Detection> det = DetectBoxes(r.cloud, options);
    if (!det.ok()) {
      ADD_FAILURE() << det.status();
      return false;
    }
    bool hit = false;
    for (const DetectedBox& b : det->boxes) {
      const PoseError nearest = AgainstNearest(b, r.boxes);
      EXPECT_LT(nearest.translation_m, 0.02) << "cap " << cap;
      EXPECT_LT(nearest.rotation_deg, 10.0) << "cap " << cap;
      const PoseError e = ComparePoses(b.camera_T_box, under.camera_T_box, carton_s);
      hit |= e.translation_m < 0.01 && e.rotation_deg < 3.0;
    }
    return hit;
  };
  EXPECT_TRUE(found(AcceptanceOptions{}.max_occluded));
  EXPECT_FALSE(found(0.3));
}

// Was: on a Kinect pallet of bricks, whose seams finer than a pixel show as
// sparse lines of missing returns on some sides and not on others, the
// chain of neighbours from the few bricks found stopped at the first brick
// with a side that ran on flat: 3 of 50 pickable bricks found in frame 2 of
// scripts/evaluate's kinect_brick_s22 set, 1 of 47 in frame 6, though the
// judge accepts most of the rest from their true poses. A brick declined
// only for a side that runs on flat now proposes its own neighbours, up to
// two such bricks in a row (DetectorOptions::neighbour_steps_past_declined),
// and the bricks' seams along their long sides turn them
// (RefinementOptions::seam_turn_min_length_m: a neighbour turned as the
// brick that proposed it no longer misses its seams); each carries the
// chain on its own. Every brick returned is still one of the pallet's.
TEST(RegressionTest, TheNeighbourChainGoesOnPastABrickWithASeamMissed) {
  const BoxDims brick{0.19, 0.09, 0.057};
  for (const int i : {2, 6}) {
    const absl::StatusOr<RenderedScene> frame = KinectFrame("touching1", brick, i, 22000 + i);
    ASSERT_TRUE(frame.ok()) << frame.status();
    const RenderedScene& r = *frame;
    const PointCloud cloud = RoundedToMillimetres(r);
    for (const auto& [past, seam_turn] : {std::pair{true, true}, std::pair{true, false},
                                          std::pair{false, true}, std::pair{false, false}}) {
      DetectorOptions options;
      options.box = brick;
      if (!past) options.neighbour_steps_past_declined = 0;
      if (!seam_turn) options.refinement.seam_turn_min_length_m = 0.0;
      // Without both, the detector the rules were made for: a third step for
      // a brick still turning, its turned readings, or the faces split out
      // of the layer along its seams carry the chain on too.
      if (!past && !seam_turn) {
        options.refinement.extra_step_corner_move_m = 0.0;
        options.turned_proposals = false;
        options.faces.seam_split.enabled = false;
        options.refinement.seam_depth_per_rms = 0.0;  // session 29's groove rule
      }
      const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
      ASSERT_TRUE(det.ok()) << det.status();
      const std::string what = absl::StrCat("frame ", i, " past ", past, " seam_turn ", seam_turn);
      if (past || seam_turn) {
        EXPECT_GE(det->boxes.size(), 20u) << what;
      } else {
        EXPECT_LE(det->boxes.size(), 6u) << what;
      }
      for (const DetectedBox& b : det->boxes) {
        const PoseError nearest = AgainstNearest(b, r.boxes);
        EXPECT_LT(nearest.translation_m, 0.02) << what;
        EXPECT_LT(nearest.rotation_deg, 10.0) << what;
      }
    }
  }
}

// Was: on a pallet of flat carton_s with boxes of other sizes on the layer,
// a box of 0.20 x 0.14 x 0.19 m standing among the cartons, its top 3 cm
// above theirs, was returned as a carton on end (its 0.20 x 0.15 end face
// is the smaller box's top within a centimetre): a wrong box, 6 cm and
// 120 degrees off, in scripts/evaluate's tof_carton_s_s24 (frame 2) and
// stereo_carton_s_s17 (frame 7). Such a carton's bottom would lie 12 cm
// below the bottoms of the cartons beside it, whose tops are level with
// its own: it would stand in a hole of what they stand on
// (DetectorOptions::max_below_neighbours_m).
TEST(RegressionTest, ABoxLevelWithItsNeighboursDoesNotReachFarBelowThem) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kTimeOfFlight, true, "touching1", carton_s, 2, 24002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  for (const double below : {0.05, 0.0}) {
    DetectorOptions options;
    options.box = carton_s;
    options.max_below_neighbours_m = below;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    const int wrong = WrongBoxes(*det, r);
    EXPECT_GE(det->boxes.size(), 10u) << "check at " << below;
    if (below > 0.0) {
      EXPECT_EQ(wrong, 0);
    } else {
      EXPECT_GE(wrong, 1) << "without the check the smaller box is a carton on end";
    }
  }
}

// Was: on a stereo pallet of touching carton_s (no colour), a carton lying
// flat was also read as a carton on end: a false seam halfway along its top
// made a 0.20 x 0.15 face of it, 10 cm and 89 degrees off. The level check
// missed it: the three cartons level with it lay 0.38-0.43 m from the
// false face's centre, beyond the touching distance of that small face;
// measured from the largest face they are its neighbours, and it is taken
// out. The frame change test's stereo pallet 3 (seed 93), as rendered
// without colour.
TEST(RegressionTest, ACartonReadOnItsEndInsideAFlatOnesTopIsTakenOut) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, false, "touching", carton_s, 3, 93);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  for (const double below : {0.05, 0.0}) {
    DetectorOptions options;
    options.box = carton_s;
    options.max_below_neighbours_m = below;
    // Session 29's groove rule (RefinementOptions::seam_depth_per_rms) off:
    // the frame as this rule was made on it (the groove rule alone changes
    // its boxes).
    options.refinement.seam_depth_per_rms = 0.0;
    // The paired check (session 33) takes this carton out too: the level
    // check alone is tested here.
    options.paired_check = false;
    const absl::StatusOr<Detection> det = DetectBoxes(r.cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    const int wrong = WrongBoxes(*det, r);
    EXPECT_GE(det->boxes.size(), 6u) << "check at " << below;
    if (below > 0.0) {
      EXPECT_EQ(wrong, 0);
    } else {
      EXPECT_GE(wrong, 1) << "without the check the carton on end is returned";
    }
  }
}

// Was: on a stereo pallet of carton_l (0.40 x 0.30 x 0.25 m) at 2.3 m, a
// box of another size (0.28 x 0.24 x 0.20 m) standing in a notch of the
// layer was read as a carton_l on its 0.30 x 0.25 end, its bottom 6.6 cm
// into the floor; the only box the frame returned. The floor check found no
// floor: the stereo noise cut it into pieces, none of them 0.36 m^2, and
// its far part lay more than 3 cm beyond any one piece's plane. Now the
// floor is the plane of all its pieces, and "beyond" allows for its
// scatter. A held-out seed of scripts/evaluate's kind (make_frames --sensor
// stereo --box carton_l --seed 35 --kind depal --color, frame 6).
TEST(RegressionTest, ABoxOfAnotherSizeReadOnEndReachesIntoANoisyFloor) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_l, 6, 35006);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  for (const bool check : {true, false}) {
    DetectorOptions options;
    options.box = carton_l;
    options.floor_check = check;
    // Without it, the detector the check was made for (a third step for a
    // face still turning, or the turned readings, read this box right too).
    if (!check) {
      options.refinement.extra_step_corner_move_m = 0.0;
      options.turned_proposals = false;
      options.edge_pairs.enabled = false;  // the face between its edges too
    }
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    const int wrong = WrongBoxes(*det, r);
    if (check) {
      EXPECT_EQ(wrong, 0);
      EXPECT_TRUE(
          std::any_of(det->declined.begin(), det->declined.end(), [](const DeclinedCandidate& d) {
            return d.reason.find("into the floor") != std::string::npos;
          }));
    } else {
      EXPECT_GE(wrong, 1) << "without the check the box on end is returned";
    }
  }
}

// Was: on a stereo pallet of carton_s (0.30 x 0.20 m tops, colour), a box
// turned a quarter across two cartons was returned: its sides a free
// border, the true seam below it, a tape edge on the neighbour's top taken
// for a seam, and one side tiled. The true carton at its corner, turned
// back, passes the judge as well; neither reading is safe, so the box is
// taken out (DetectorOptions::turned_check). Frame touching1_002 of
// scripts/evaluate's stereo carton_s set of seed 17.
TEST(RegressionTest, ABoxThatReadsAsWellTurnedAtItsCornerIsTakenOut) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_s, 2, 17002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  for (const bool check : {true, false}) {
    DetectorOptions options;
    options.box = carton_s;
    options.turned_check = check;
    // Without it, the refinement of two steps the check was made for (a
    // third step for a face still turning reads this box right as well).
    if (!check) options.refinement.extra_step_corner_move_m = 0.0;
    // Session 29's groove rule (RefinementOptions::seam_depth_per_rms) off:
    // the frame as this rule was made on it (the groove rule alone changes
    // its boxes).
    options.refinement.seam_depth_per_rms = 0.0;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    EXPECT_GE(det->boxes.size(), 8u) << "check " << check;
    if (check) {
      EXPECT_EQ(WrongBoxes(*det, r), 0);
    } else {
      EXPECT_GE(WrongBoxes(*det, r), 1) << "without the check the turned box is returned";
    }
  }
}

// Was: in a Kinect heap of square cartons (0.25 x 0.25 x 0.20 m; frame 5 of
// make_frames --sensor kinect --box carton_sq --seed 44), a carton lying
// flat with the far part of its top in the shadow of a nearer carton was
// returned as a carton on its side: its face read 0.20 x 0.25 m, three sides
// free and the fourth with nothing seen near it. An unseen side now counts
// as hidden where a longer side of the box could stand
// (AcceptanceOptions::check_unseen_sides). The same frame's other wrong box,
// a carton lying on its 0.25 x 0.20 side read as its 0.25 x 0.25 end (35 mm
// off, the fourth side unseen: half of the pixels just inside it in the
// shadow of a box in front, the rest seeing the floor behind the face), is
// declined since session 24: that side is seen through
// (RefinementOptions::seen_through_share).
TEST(RegressionTest, ACartonWhoseTopEndsInAShadowIsNotReadOnItsSide) {
  const BoxDims carton_sq{0.25, 0.25, 0.20};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("heap", carton_sq, 5, 44005);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const PointCloud cloud = RoundedToMillimetres(*frame);
  auto wrong = [&](bool check, double seen_through = RefinementOptions{}.seen_through_share) {
    DetectorOptions options;
    options.box = carton_sq;
    options.acceptance.check_unseen_sides = check;
    options.refinement.seen_through_share = seen_through;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    if (!det.ok()) {
      ADD_FAILURE() << det.status();
      return -1;
    }
    return WrongBoxes(*det, *frame);
  };
  // Without the check the carton on its side is among the wrong boxes; with
  // it, it is not; without the seen-through rule the end read for a side
  // is.
  EXPECT_GE(wrong(false), 1);
  EXPECT_EQ(wrong(true), 0);
  EXPECT_EQ(wrong(true, 0.0), 1);
  EXPECT_GE(wrong(false, 0.0), 2);
}

// Was: on a stereo pallet of five carton_l and a smaller box (frame 6 of
// make_frames --sensor stereo --box carton_l --seed 35 --color, the frame
// of the floor test above) nothing was returned, though the judge accepts
// every carton from its true pose: the only corner hypotheses near them
// started 2-5 degrees off, ended two refinement steps still 2 degrees off,
// and the far ends of their 0.40 m sides, read a centimetre off, ran on.
// A third step for a face still turning
// (RefinementOptions::extra_step_corner_move_m) lands the first carton,
// and its neighbours follow.
TEST(RegressionTest, AFaceStillTurningAfterTwoStepsGetsAThird) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_l, 6, 35006);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  auto found = [&](double corner_move) {
    DetectorOptions options;
    options.box = carton_l;
    options.refinement.extra_step_corner_move_m = corner_move;
    // The turned readings of the declined hypotheses and the faces between
    // parallel edges find these cartons as well: without them, the step
    // alone.
    options.turned_proposals = false;
    options.edge_pairs.enabled = false;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    if (!det.ok()) {
      ADD_FAILURE() << det.status();
      return -1;
    }
    EXPECT_EQ(WrongBoxes(*det, r), 0) << corner_move;
    return static_cast<int>(det->boxes.size());
  };
  EXPECT_EQ(found(0.0), 0);
  EXPECT_GE(found(RefinementOptions{}.extra_step_corner_move_m), 5);
}

// Was: a Kinect pallet of carton_flat (0.30 x 0.20 x 0.10 m) whose layer
// ran past the image's top and bottom returned nothing, though the judge
// accepts seven of its nine pickable cartons from their true poses: the
// layer's corners were out of view (no corner hypotheses), its outline cut
// by the border tiles nothing, and no corner of it ends in depth jumps for
// the anchored faces. The seams between its cartons showed as lines of
// missing returns across the layer; split along them
// (FaceProposalOptions::seam_split), it proposes the cartons between them.
// A held-out seed of scripts/evaluate's kind (make_frames --sensor kinect
// --box carton_flat --seed 57 --kind depal, frame 6).
TEST(RegressionTest, ALayerCutByTheBorderIsSplitAlongTheSeamsItShows) {
  const BoxDims carton_flat{0.30, 0.20, 0.10};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kKinect, false, "touching1", carton_flat, 6, 57006);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  auto found = [&](bool split) {
    DetectorOptions options;
    options.box = carton_flat;
    options.faces.seam_split.enabled = split;
    // Without the split, a carton with a corner just past the border is
    // found since session 30 (max_out_of_view_share): off, to test the
    // split on its own.
    options.acceptance.max_out_of_view_share = 0.0;
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    if (!det.ok()) {
      ADD_FAILURE() << det.status();
      return -1;
    }
    EXPECT_EQ(WrongBoxes(*det, r), 0) << split;
    return static_cast<int>(det->boxes.size());
  };
  EXPECT_EQ(found(false), 0);
  EXPECT_GE(found(true), 4);
}

// A one-layer pallet of bricks on a EUR pallet: between the layer's ends
// and the pallet's, 0.2 m of the deck boards show, the layer standing over
// their far end, and a 0.10 m board segment there, bounded by the 4 cm gaps
// to the boards beside it and the pallet's edge, reads as a brick (0.19 x
// 0.09 m) lying flat, every one of its sides measured; in the time-of-flight
// frame it was the best-scoring box. Its long sides are free, but past each
// gap the deck's plane goes on (RefinementOptions::slat_gap_max_m): a board,
// not a box. Held-out frames of the dev kinds (make_frames --kind mixed,
// frame 5 of seed 73; --kind pallet --sensor tof --color, frame 5 of seed
// 84).
TEST(RegressionTest, ADeckBoardBetweenTwoGapsIsNoBox) {
  const BoxDims brick{0.19, 0.09, 0.057};
  for (const auto& [sensor, color, seed] : {std::tuple{SensorKind::kKinect, false, 73005u},
                                            std::tuple{SensorKind::kTimeOfFlight, true, 84005u}}) {
    const absl::StatusOr<RenderedScene> frame =
        SensorFrame(sensor, color, "pallet", brick, 5, seed);
    ASSERT_TRUE(frame.ok()) << frame.status();
    const RenderedScene& r = *frame;
    const PointCloud cloud = RoundedToMillimetres(r);
    for (const double slat_gap : {0.06, 0.0}) {
      DetectorOptions options;
      options.box = brick;
      options.refinement.slat_gap_max_m = slat_gap;
      const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
      ASSERT_TRUE(det.ok()) << det.status();
      const int wrong = WrongBoxes(*det, r);
      const int right = static_cast<int>(det->boxes.size()) - wrong;
      if (slat_gap > 0.0) {
        EXPECT_EQ(wrong, 0) << seed;
        EXPECT_GE(right, 12) << seed;
        ASSERT_FALSE(det->boxes.empty());
        EXPECT_LT(AgainstNearest(det->boxes[0], r.boxes).translation_m, 0.02) << seed;
      } else {
        EXPECT_GE(wrong, 1) << seed;  // the rule is what takes them out
      }
    }
  }
}

// A pallet layer of 4 x 4 carton_l (1.6 x 1.2 m, as the dev set's own
// generator lays them: dev_004 is a 4 x 2 grid of them) filling a Kinect
// frame, cut by the border on every side, its seams plain lines of missing
// returns: no corner in view and an outline that tiles nothing, so only
// the seam split proposes its cartons. Its outline measured 1.607 m, past
// the split's limit for patches (then 1.6 m, meant to spare a floor's scan):
// nothing was returned though the judge accepts seven cartons from their
// true poses. A held-out frame of the dev kinds (make_frames --kind mixed
// --box carton_l, frame 5 of seed 76).
TEST(RegressionTest, ALayerOfLongCartonsIsSplitAlongItsSeams) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kKinect, false, "pallet", carton_l, 5, 76005);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  for (const double max_side : {2.0, 1.6}) {
    DetectorOptions options;
    options.box = carton_l;
    options.faces.seam_split.max_side_m = max_side;
    options.empty_frame_window_cells = 0;  // the split alone, no second look
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
    ASSERT_TRUE(det.ok()) << det.status();
    EXPECT_EQ(WrongBoxes(*det, r), 0) << max_side;
    if (max_side > 1.6) {
      EXPECT_GE(det->boxes.size(), 5u);
    } else {
      EXPECT_TRUE(det->boxes.empty());
    }
  }
}

// Was: a Kinect view filled by a pallet layer of 4 x 4 carton_l, 14 of
// them pickable (>= 75 % of the top in view), returned the 5 whose tops lay
// whole in the image: every carton the image border cuts was declined
// "grasp face cut by the image border" or "no free side and not boxed in by
// seams on all four", its three other sides measured. Now a face seen on
// its plane from a measured end to the border for longer than any shorter
// side of the box, and over 60 % of its length, is pinned up to the border
// (AcceptanceOptions::face_may_run_out_of_view): the cartons at the view's
// left and right are returned where they are; with the rule off, three
// fewer. scripts/evaluate's kinect_carton_l_s86 set, frame 5.
TEST(RegressionTest, PalletCartonsTheBorderCutsArePinnedByWhatIsInView) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kKinect, false, "pallet", carton_l, 5, 86005);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      cloud, r, carton_l,
      [](bool on, DetectorOptions* o) { o->acceptance.face_may_run_out_of_view = on; });
  std::array<int, 2> cut{0, 0};  // rule off, on
  for (const bool on : {false, true}) {
    for (const DetectedBox& b : det[on].boxes) cut[on] += CutByBorder(r, carton_l, b);
  }
  EXPECT_GE(det[1].boxes.size(), 8u);
  // Off, only a carton ended on every side (PinnedOnEverySide) may leave
  // the view.
  EXPECT_GE(cut[1], cut[0] + 3);
}

// Was: on a Kinect pallet of carton_l touching in a row, the carton beside
// one found showed no seam toward it (the sensor's speckle left none there)
// and was declined "a side runs on flat", its three other sides ended by
// seams and free borders. Now a side running on flat that lies against the
// grasp face of a box already kept, coplanar and aligned, is a seam
// (AcceptanceOptions::kept_box_ends_side): the frame's four pickable
// cartons are returned, none wrong; with the rule off, three.
// scripts/evaluate's kinect_carton_l_s4 set, frame 2.
TEST(RegressionTest, ACartonBesideOneFoundIsEndedByItWhereNoSeamShows) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("touching1", carton_l, 2, 4002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det =
      DetectedWithRuleOffAndOn(cloud, r, carton_l, [](bool on, DetectorOptions* o) {
        o->acceptance.kept_box_ends_side = on;
        o->turned_proposals = true;  // as the rule was made (off since session 36)
      });
  EXPECT_GE(det[1].boxes.size(), 4u);
  EXPECT_GT(det[1].boxes.size(), det[0].boxes.size());
  EXPECT_GE(DefaultsReturnNoWrongBox(cloud, r, carton_l), 4u);
}

// Was: on a Kinect pallet layer of carton_l, two cartons side by side whose
// shared seam shows nothing (no missing returns, no kept box beside either)
// were both declined "a side runs on flat", every other side of both ended
// by seams and free borders. Now two such hypotheses whose flat sides lie
// against each other's face end each other
// (AcceptanceOptions::pairs_end_each_other): both are judged again with the
// other taken as kept, and kept when both pass. Two cartons more, none
// wrong. A held-out set of the dev kinds (make_frames --kind pallet --seed
// 96), frame 8.
TEST(RegressionTest, TwoCartonsWhoseSharedSeamShowsNothingEndEachOther) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kKinect, false, "pallet", carton_l, 8, 96008);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      cloud, r, carton_l,
      [](bool on, DetectorOptions* o) { o->acceptance.pairs_end_each_other = on; });
  EXPECT_GE(det[1].boxes.size(), det[0].boxes.size() + 2);
}

// Two bricks side by side along their 9 cm sides make a 0.19 x 0.19 m
// square, which tiles as well with the two bricks turned a quarter: a pair
// that ends each other there (AcceptanceOptions::pairs_end_each_other)
// must tile its outline one way only, or both are declined. Without that
// test two turned bricks were returned on this Kinect brick layer.
// scripts/evaluate's kinect_brick_s22 set, frame 2.
TEST(RegressionTest, APairOfBricksWhoseOutlineTilesTwoWaysIsNotKept) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("touching1", brick, 2, 22002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  DetectorOptions options;
  options.box = brick;
  const absl::StatusOr<Detection> det = DetectBoxes(RoundedToMillimetres(r), options);
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_EQ(WrongBoxes(*det, r), 0);
  EXPECT_GE(det->boxes.size(), 37u);
}

// Was: a pallet of 4 x 3 carton_s at 2.1-2.5 m from a stereo camera (about
// 1 cm of depth noise there) returned nothing: the layer came out of the
// 7 x 7-cell normal window in pieces too small to propose a face, and two
// corners were found in the whole frame, though the judge accepts all 12
// cartons from their true poses. Now a frame in which nothing is found is
// detected once more with a 9 x 9-cell window
// (DetectorOptions::empty_frame_window_cells): all 12, none wrong; with it
// 0, nothing. A held-out set of the dev kinds (make_frames --sensor stereo
// --kind mixed --color --seed 106), frame 8. The first look of 1 000
// samples it was found with: with session 35's 400 the 7 x 7 window already
// found its cartons; with session 36's three readings per corner it needs
// the second look again.
TEST(RegressionTest, AFarStereoPalletThatReturnedNothingIsDetectedWithAWiderWindow) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "pallet", carton_s, 8, 106008);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, carton_s, [](bool on, DetectorOptions* o) {
        o->empty_frame_window_cells = on ? 4 : 0;
        o->evidence.gate_max_samples = 1000;
      });
  EXPECT_TRUE(det[0].boxes.empty());
  EXPECT_GE(det[1].boxes.size(), 10u);
  // With session 35's 400-sample first look the first window finds all 12
  // from the corners' every reading; since session 36 a corner proposes its
  // three best (PoseOptions::max_readings_per_corner), the cartons' noisy
  // edges (1 cm at 2.3 m) rank their readings lower, and the first window
  // finds nothing again: the second look finds all 12, as with the defaults.
  auto detect = [&](const std::function<void(DetectorOptions*)>& set) {
    DetectorOptions o;
    o.box = carton_s;
    set(&o);
    absl::StatusOr<Detection> d = DetectBoxes(RoundedToMillimetres(r), o);
    EXPECT_TRUE(d.ok()) << d.status();
    if (d.ok()) EXPECT_EQ(WrongBoxes(*d, r), 0);
    return d.ok() ? d->boxes.size() : 0u;
  };
  // Session 35's detector, the first window only: every reading, turned
  // proposals on.
  EXPECT_GE(detect([](DetectorOptions* o) {
              o->empty_frame_window_cells = 0;
              o->pose.max_readings_per_corner = 0;
              o->turned_proposals = true;
            }),
            10u);
  // Three readings per corner, the first window only.
  EXPECT_EQ(detect([](DetectorOptions* o) {
              o->empty_frame_window_cells = 0;
              o->pose.max_readings_per_corner = 3;
            }),
            0u);
  EXPECT_GE(detect([](DetectorOptions*) {}), 10u);  // the defaults
}

// Was: on a Kinect pallet of bricks a brick was accepted by the judge but
// not kept, a reading kept before it overlapping it; a plausibility check
// then took that reading out, and the brick stayed lost. Now the readings
// a box taken out had outranked are judged again
// (DetectorOptions::retake_outranked): one brick more, none wrong.
// A held-out frame of the dev kinds (make_frames --sensor kinect --box
// brick --kind pallet, frame 2 of seed 93).
TEST(RegressionTest, AReadingOutrankedByABoxTakenOutIsJudgedAgain) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kKinect, false, "pallet", brick, 2, 93002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det =
      DetectedWithRuleOffAndOn(cloud, r, brick, [](bool on, DetectorOptions* o) {
        o->retake_outranked = on;
        o->refinement.seam_depth_per_rms = 0.0;  // session 29's groove rule
        o->pose.max_readings_per_corner = 0;     // every reading of a corner, as then
      });
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size() + 1);
}

// Was: in a heap, a carton lying free on the floor was declined for a side
// that "runs on flat": a neighbour's face crossing the carton's plane at
// one corner put 0.15 of the side's inner points past it, though the face
// ended at the side along three quarters of it (RefinementOptions::
// side_ends_share). ToF carton_sq s6 heap_001 of scripts/evaluate: one box
// more with the rule, none wrong either way.
TEST(RegressionTest, ASideTheFaceEndsAtAlongMostOfItIsFree) {
  const BoxDims carton_sq{0.25, 0.25, 0.20};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kTimeOfFlight, true, "heap", carton_sq, 1, 6001);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      cloud, r, carton_sq,
      [](bool on, DetectorOptions* o) { o->refinement.side_ends_share = on ? 0.67 : 0.0; });
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size() + 1);
}

// Was: bricks in a heap whose short ends lie in shadows (nothing seen near
// them) were declined: a brick lying the other way, its face running on
// into the shadow, could stand in. Where the floor shows past the shadow
// (AcceptanceOptions::unseen_longer_see_through) it cannot. Kinect brick
// s73 heap_004 of scripts/evaluate: two bricks more, none wrong.
TEST(RegressionTest, ABrickWhoseLongerReadingTheFloorRulesOutIsFound) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("heap", brick, 4, 73004);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det =
      DetectedWithRuleOffAndOn(cloud, r, brick, [](bool on, DetectorOptions* o) {
        o->acceptance.unseen_longer_see_through = on ? 0.2 : 0.0;
      });
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size() + 2);
}

// Was: a stereo carton at the image's left border, three sides free, was
// declined as cut by the border: toward the border the face showed on its
// plane, then 4 cm of the stereo camera's band with no return, counted as
// off the face, so no line saw it past the 0.25 m of the box's other face.
// The band now ends the view (AcceptanceOptions::border_band_ends_view).
// Stereo carton_l s8 heap_005 of scripts/evaluate: one box more, none
// wrong either way.
TEST(RegressionTest, AStereoCartonCutByTheBorderBesideItsBandOfNoReturnsIsFound) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "heap", carton_l, 5, 8005);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, carton_l,
      [](bool on, DetectorOptions* o) { o->acceptance.border_band_ends_view = on; });
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size() + 1);
}

// Was: in a stereo heap of bricks at 1.6 m, bricks outlined by edge
// segments on every side had no corner: the two lines of a corner passed
// 1-3 cm apart in depth (the camera's noise, along the line of sight),
// beyond the 1 cm a corner's lines may be apart. Along the line of sight
// they may now be three times that (ClubbingOptions::
// meet_along_view_factor; with a colour image). Stereo brick s19 heap_001
// of scripts/evaluate: two bricks more, none wrong either way.
TEST(RegressionTest, CornersOfStereoBricksMeetAcrossTheirDepthNoise) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "heap", brick, 1, 19001);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const PointCloud cloud = RoundedToMillimetres(r);
  const std::array<Detection, 2> det =
      DetectedWithRuleOffAndOn(cloud, r, brick, [](bool on, DetectorOptions* o) {
        o->clubbing.meet_along_view_factor = on ? 3.0 : 1.0;
        o->edge_pairs.enabled = false;  // they find the bricks' faces between their edges too
      });
  EXPECT_GT(det[1].corners.size(), det[0].corners.size());
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size() + 2);
  // Without its colour image the frame keeps the paper's sphere at the
  // defaults (the judge cannot check the readings more corners propose).
  PointCloud depth_only = cloud;
  depth_only.rgb.clear();
  DetectorOptions defaults;
  defaults.box = brick;
  const absl::StatusOr<Detection> plain = DetectBoxes(depth_only, defaults);
  defaults.clubbing.meet_along_view_factor = 1.0;
  const absl::StatusOr<Detection> sphere = DetectBoxes(depth_only, defaults);
  ASSERT_TRUE(plain.ok() && sphere.ok());
  EXPECT_EQ(plain->corners.size(), sphere->corners.size());
  EXPECT_EQ(plain->boxes.size(), sphere->boxes.size());
}

// Was: an isolated stereo carton, refined from its four corners, was
// declined for a side that runs on flat: the fattened rim past that side
// read as a groove (a seam), the colour image showed no line there, so the
// seam was dropped, and the side was left running on with no measure of
// where the face ends: the rim rule (RefinementOptions::rim_ends_side)
// could not free it. The rim is now measured for a seam too. Stereo carton_s
// s34 isolated_000 of scripts/evaluate.
TEST(RegressionTest, AStereoRimWhoseGrooveTheColourDropsIsFree) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "isolated", carton_s, 0, 34000);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  DetectorOptions options;
  options.box = carton_s;
  const absl::StatusOr<Detection> det = DetectBoxes(RoundedToMillimetres(r), options);
  ASSERT_TRUE(det.ok()) << det.status();
  ASSERT_EQ(det->boxes.size(), 1u);
  EXPECT_EQ(WrongBoxes(*det, r), 0);
}

// Was: on a stereo pallet of carton_s with boxes of other sizes on the
// layer, a 0.18 x 0.13 x 0.13 m box at the layer's corner was returned as a
// carton on its 0.20 x 0.15 end: 1.4 and 2.2 cm short, each within the
// 2.5 cm an axis may be off. Short both ways it is a smaller box
// (AcceptanceOptions::max_short_both_axes_m). Stereo carton_s s55
// touching1_002 of scripts/evaluate.
TEST(RegressionTest, AFaceShortOfTheBoxBothWaysIsNotReturned) {
  const BoxDims carton_s{0.30, 0.20, 0.15};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_s, 2, 55002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, carton_s,
      [](bool on, DetectorOptions* o) { o->acceptance.max_short_both_axes_m = on ? 0.012 : 0.0; },
      /*wrong_without=*/true);
  EXPECT_GE(det[0].boxes.size(), 12u);
  EXPECT_GE(det[1].boxes.size(), 12u);
}

// Was: on a stereo pallet of carton_flat (0.30 x 0.20 x 0.10 m) cut by the
// image border, a carton lying flat with a tape edge halfway across its
// top was also returned as one on its 0.30 x 0.10 side (the seam to the
// carton beside it and the tape edge its long sides): its bottom would lie
// 10 cm below that neighbour's, whose top is level with its own, but the
// level check wanted two such neighbours. One the box lies flush against
// (touching, its sides aligned) is a layer on its own (DetectorOptions::
// flush_neighbour_is_layer). Stereo carton_flat s65 touching1_002 of
// scripts/evaluate.
TEST(RegressionTest, ABoxOnItsSideFlushAgainstALevelBoxIsTakenOut) {
  const BoxDims carton_flat{0.30, 0.20, 0.10};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_flat, 2, 65002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, carton_flat,
      [](bool on, DetectorOptions* o) {
        o->flush_neighbour_is_layer = on;
        // As the rule was made (since then the shifted check and a lower
        // side_ends_share change which reading of the layer is kept first).
        o->refinement.side_ends_share = 0.67;
        o->shifted_check = false;
        // Every reading of a corner (since session 36 a corner proposes its
        // three best, and the one on its side is no longer proposed).
        o->pose.max_readings_per_corner = 0;
      },
      /*wrong_without=*/true);
  EXPECT_GE(det[0].boxes.size(), 10u);
  EXPECT_GE(det[1].boxes.size(), 10u);
}

// Was: on the same stereo carton_flat pallet, with a side read free where
// the face ends along 0.55 of it (RefinementOptions::side_ends_share), a
// carton straddling two was returned: its long sides the tape edges along
// the middle of both cartons' flaps (colour lines), one end the pallet's
// edge. Shifted half its width across those two seams it is the carton
// ended by the pallet's edge on two sides, judged a box with more free
// sides: it is taken out (DetectorOptions::shifted_check), and the two
// cartons it outranked are kept.
TEST(RegressionTest, ACartonStraddlingTwoOnTheirTapeEdgesIsTakenOut) {
  const BoxDims carton_flat{0.30, 0.20, 0.10};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_flat, 2, 65002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, carton_flat,
      [](bool on, DetectorOptions* o) {
        o->shifted_check = on;
        o->refinement.side_ends_share = 0.55;
        o->pose.max_readings_per_corner = 0;  // as the rule was made
        o->turned_proposals = true;
      },
      /*wrong_without=*/true);
  EXPECT_GT(det[1].boxes.size(), det[0].boxes.size());
  EXPECT_GE(DefaultsReturnNoWrongBox(RoundedToMillimetres(r), r, carton_flat), 10u);
}

// Was: a brick in a heap, lying on its side beside another whose face is
// level with its own and set off along the side they share, was declined
// for a side that runs on flat: its face ended there along less than 0.55
// of the side (RefinementOptions::side_ends_share, 0.35 since session 29).
// Kinect brick s22 heap_001 of scripts/evaluate --more: one box more, none
// wrong either way.
TEST(RegressionTest, ABrickBesideALevelOneSetOffAlongItIsFound) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("heap", brick, 1, 22001);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det =
      DetectedWithRuleOffAndOn(RoundedToMillimetres(r), r, brick, [](bool on, DetectorOptions* o) {
        o->refinement.side_ends_share = on ? 0.35 : 0.55;
        o->refinement.seam_depth_per_rms = 0.0;  // session 29's groove rule, measured apart
        o->edge_pairs.enabled = false;           // the face between its edges finds it too
      });
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size() + 1);
}

// Was (with side_ends_share below 0.55 and nothing more): two bricks lying
// in an L, their tops level, held a reading across both, turned a quarter,
// that ended along part of one side and had two sides hidden; it was
// returned 62 mm and 91 degrees off the brick under it. A side so found
// free along less than side_ends_alone_share of it now needs two of the
// face's other sides measured. Kinect brick s403 heap_001 of scripts/
// evaluate --wide.
TEST(RegressionTest, AReadingAcrossTwoBricksInAnLIsNotReturned) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("heap", brick, 1, 403001);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, brick,
      [](bool on, DetectorOptions* o) { o->refinement.side_ends_alone_share = on ? 0.55 : 0.0; },
      /*wrong_without=*/true);
}

// Was: a Kinect's disparity steps lay stripes a step high across a flat
// deck board of a EUR pallet, and one running along a side of a brick-sized
// piece of the board (beside the layer of bricks, a deck gap on its other
// side) read as a 1.6 mm groove, over the 1.5 mm a seam needed: the piece
// was returned as a brick. A groove must now be deeper than the face's own
// RMS about its plane (RefinementOptions::seam_depth_per_rms). Kinect brick
// s403 pallet_002 of scripts/evaluate --wide.
TEST(RegressionTest, ADisparityStripeOnADeckBoardIsNoSeam) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame = KinectFrame("pallet", brick, 2, 403002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, brick,
      [](bool on, DetectorOptions* o) { o->refinement.seam_depth_per_rms = on ? 1.0 : 0.0; },
      /*wrong_without=*/true);
  EXPECT_GE(det[1].boxes.size(), 10u);
}

// Was: in a ToF pallet layer of bricks, a neighbour proposed from a brick
// of the layer came out turned 10.4 degrees in its plane (its turn read
// from its seams alone) while its three touching neighbours lay within a
// degree of the grid: a wrong box. Boxes of a layer now take its turn
// (layer_turn.h). ToF brick s613 touching2_007, rendered in session 32
// after the rules were set.
TEST(RegressionTest, ABrickTurnedAgainstItsLayerTakesTheLayersTurn) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kTimeOfFlight, true, "touching2", brick, 7, 613007);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, brick,
      [](bool on, DetectorOptions* o) { o->layer_turn.min_agreeing = on ? 3 : 0; },
      /*wrong_without=*/true);
  // It changes poses, never which boxes are returned.
  EXPECT_EQ(det[1].boxes.size(), det[0].boxes.size());
}

// Was: on a stereo pallet of carton_flat (0.30 x 0.20 x 0.10: its height
// half its width), the tops of two cartons, each split along its flap seam
// into two faces the size of the carton's side, were returned as two pairs
// of cartons on their side, 7 cm off and turned a quarter, the best box of
// the frame among them. Such a pair, whose faces together are a carton's
// top, is taken out when that one carton is judged a box too
// (DetectorOptions::paired_check), and the cartons are found lying flat.
// Stereo carton_flat s725 touching1_006, rendered in session 33 after the
// rules were set.
TEST(RegressionTest, TwoCartonsOnTheirSideThatAreOneCartonsTopAreTakenOut) {
  const BoxDims carton_flat{0.30, 0.20, 0.10};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, true, "touching1", carton_flat, 6, 725006);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  const std::array<Detection, 2> det = DetectedWithRuleOffAndOn(
      RoundedToMillimetres(r), r, carton_flat,
      [](bool on, DetectorOptions* o) {
        o->paired_check = on;
        o->pose.max_readings_per_corner = 0;  // as the rule was made: every reading,
        o->turned_proposals = true;           // turned proposals on
      },
      /*wrong_without=*/true);
  // The cartons the pairs stood for are found instead.
  const auto right = [&](const Detection& d) {
    return static_cast<int>(d.boxes.size()) - WrongBoxes(d, r);
  };
  EXPECT_GT(right(det[1]), right(det[0]));
  DefaultsReturnNoWrongBox(RoundedToMillimetres(r), r, carton_flat);
}

// Was: a brick alone on the floor, seen by the active stereo camera, came
// out 7-8 degrees tilted about its long axis (its 9 cm top smoothed with the
// floor beside it): found at 20 mm / 10 degrees, not at 10 mm / 5. Its
// bottom so turned reached into the floor found; it now lies flat on it
// (DetectorOptions::floor_rest). Stereo brick s723 isolated_000 and
// isolated_004, rendered in session 33.
TEST(RegressionTest, AStereoBrickAloneOnTheFloorLiesFlatOnIt) {
  const BoxDims brick{0.19, 0.09, 0.057};
  for (const int i : {0, 4}) {
    const absl::StatusOr<RenderedScene> frame =
        SensorFrame(SensorKind::kStereo, true, "isolated", brick, i, 723000 + i);
    ASSERT_TRUE(frame.ok()) << frame.status();
    const RenderedScene& r = *frame;
    std::array<double, 2> rotation_deg{};  // rule off, on
    for (const bool on : {false, true}) {
      DetectorOptions options;
      options.box = brick;
      if (!on) options.floor_rest.max_tilt_deg = 0.0;
      const absl::StatusOr<Detection> det = DetectBoxes(RoundedToMillimetres(r), options);
      ASSERT_TRUE(det.ok()) << det.status();
      ASSERT_EQ(det->boxes.size(), 1u) << "frame " << i << (on ? " on" : " off");
      const PoseError e = AgainstNearest(det->boxes[0], r.boxes);
      EXPECT_LT(e.translation_m, 0.01) << "frame " << i;
      rotation_deg[on] = e.rotation_deg;
    }
    EXPECT_GT(rotation_deg[0], 5.0) << "frame " << i << ": tilted without the rule";
    EXPECT_LT(rotation_deg[1], 2.5) << "frame " << i << ": flat with it";
  }
}

// Was: on an active stereo frame without colour of a brick pallet at 2 m,
// the floor beside the pallet (2-2.5 m away) came out of the segmentation
// in pieces of 0.04-0.06 m^2 whose own planes, tilted several degrees by
// the noise, gathered no floor; the pallet's top was the farthest plane and
// had most of the frame beyond it, so no floor was found, and a brick on
// end read on a 9 x 6 cm piece of the bare floor (reaching 19 cm into it)
// was the best box of the frame, 42 cm from any brick. The floor's pieces
// are now gathered again about the plane they fit together (FindFloor).
// Stereo brick s832 touching1_002 without colour, rendered in session 33.
TEST(RegressionTest, NoBrickIsReadOnAPieceOfANoisyFloor) {
  const BoxDims brick{0.19, 0.09, 0.057};
  const absl::StatusOr<RenderedScene> frame =
      SensorFrame(SensorKind::kStereo, false, "touching1", brick, 2, 832002);
  ASSERT_TRUE(frame.ok()) << frame.status();
  const RenderedScene& r = *frame;
  DetectorOptions options;
  options.box = brick;
  const absl::StatusOr<Detection> det = DetectBoxes(RoundedToMillimetres(r), options);
  ASSERT_TRUE(det.ok()) << det.status();
  for (const DetectedBox& b : det->boxes) {
    EXPECT_LT(AgainstNearest(b, r.boxes).translation_m, 0.10)
        << "a box far from every brick, at " << b.grasp_centre_camera.transpose();
  }
}

// Was: on active stereo brick pallets, a brick beside a layer of bricks
// found came out 12-14 degrees tilted (its 9 cm face under a blob of the
// camera's correlated noise), while the truth lies level with the layer;
// its pixels fit the layer's plane a little worse than the 1.3 x their own
// rms the shared layer plane asked of a face tilted past 12 degrees. Its
// face centre lies 2 mm off the layer's plane, where so tilted one side
// would lie inside the layer: it now takes the plane within 2 x
// (LayerPlaneOptions::rest_share). Stereo brick s723 touching2_007 and
// s823 touching1_002, rendered in session 33.
TEST(RegressionTest, AStereoBrickTiltedByNoiseBesideItsLayerTakesTheLayersPlane) {
  const BoxDims brick{0.19, 0.09, 0.057};
  for (const auto& [kind, index, seed] :
       {std::tuple{"touching2", 7, 723007}, std::tuple{"touching1", 2, 823002}}) {
    const absl::StatusOr<RenderedScene> frame =
        SensorFrame(SensorKind::kStereo, true, kind, brick, index, seed);
    ASSERT_TRUE(frame.ok()) << frame.status();
    const RenderedScene& r = *frame;
    std::array<int, 2> tilted{}, returned{};  // rule off, on
    for (const bool on : {false, true}) {
      DetectorOptions options;
      options.box = brick;
      if (!on) options.layer_plane.rest_share = 0.0;
      const absl::StatusOr<Detection> det = DetectBoxes(RoundedToMillimetres(r), options);
      ASSERT_TRUE(det.ok()) << det.status();
      returned[on] = static_cast<int>(det->boxes.size());
      for (const DetectedBox& b : det->boxes) {
        const PoseError e = AgainstNearest(b, r.boxes);
        tilted[on] += e.translation_m < 0.02 && e.rotation_deg > 10.0;
      }
    }
    EXPECT_GE(tilted[0], 1) << seed << ": a brick tilted without the rule";
    EXPECT_EQ(tilted[1], 0) << seed << ": none with it";
    EXPECT_EQ(returned[1], returned[0]) << seed << ": the same boxes";
  }
}

}  // namespace
}  // namespace cornerpose::testing
