// End to end with face proposals: pallet layers of touching cartons rendered
// with the Kinect model, corner-only against corner + face proposals, and
// with a colour image (per-box shade, darker seams, labels) registered to
// the depth.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <random>

#include "common/perception/detector.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

const BoxDims kCarton{0.30, 0.20, 0.15};

struct Counts {
  int pickable = 0, found = 0, returned = 0, correct = 0, top_wrong = 0;
};

void Score(const RenderedScene& r, const Detection& det, Counts* c) {
  auto near = [&](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    const PoseError e = ComparePoses(a, b, kCarton);
    return e.translation_m < 0.02 && e.rotation_deg < 10.0;
  };
  for (size_t i = 0; i < det.boxes.size(); ++i) {
    ++c->returned;
    const bool ok = std::any_of(r.boxes.begin(), r.boxes.end(), [&](const GroundTruthBox& g) {
      return g.target && near(det.boxes[i].camera_T_box, g.camera_T_box);
    });
    c->correct += ok;
    if (i == 0 && !ok) ++c->top_wrong;
  }
  for (const GroundTruthBox& g : r.boxes) {
    if (!g.pickable) continue;
    ++c->pickable;
    c->found += std::any_of(det.boxes.begin(), det.boxes.end(), [&](const DetectedBox& b) {
      return near(b.camera_T_box, g.camera_T_box);
    });
  }
}

// Cardboard colour from the instance mask: a shade per box, the support and
// floor darker, a dark line where two boxes meet, and a printed label on
// some boxes.
void PaintColour(RenderedScene* r, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> shade(-12, 12);
  std::vector<int> box_shade(256);
  for (int& s : box_shade) s = 160 + shade(rng);
  const int w = r->camera.width, h = r->camera.height;
  r->cloud.rgb.assign(r->cloud.size(), 0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      const uint8_t id = r->instance[i];
      int g = id == 0 ? 90 : id == 255 ? 120 : box_shade[id];
      bool seam = false;
      for (int d = 1; d <= 1; ++d) {
        if (u + d < w && r->instance[i + d] != id) seam = true;
        if (v + d < h && r->instance[i + static_cast<size_t>(d) * w] != id) seam = true;
      }
      if (seam && id != 0 && id != 255) g = 70;
      // A label: a dark block in one quarter of odd boxes' faces.
      if (id != 0 && id != 255 && id % 2 == 1 && (u / 9 + v / 7) % 5 == 0 && r->face[i] == 5) {
        g = std::max(30, g - 80);
      }
      const uint32_t c = static_cast<uint32_t>(std::clamp(g, 0, 255));
      r->cloud.rgb[i] = (c << 16) | (c << 8) | c;
    }
  }
}

DetectorOptions Options(bool faces) {
  DetectorOptions o;
  o.box = kCarton;
  o.face_proposals = faces;
  return o;
}

TEST(FaceDetectionTest, FaceProposalsAddPalletBoxesWithoutWrongOnes) {
  Counts corner_only, with_faces, with_colour;
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    RenderedScene r = Render(MakePalletScene(kCarton, 3 + seed % 2, 3, 1 + seed % 2, 0.002,
                                             static_cast<int>(seed % 3), seed));
    absl::StatusOr<Detection> a = DetectBoxes(r.cloud, Options(false));
    absl::StatusOr<Detection> b = DetectBoxes(r.cloud, Options(true));
    ASSERT_TRUE(a.ok() && b.ok());
    Score(r, *a, &corner_only);
    Score(r, *b, &with_faces);
    for (const DeclinedCandidate& d : b->declined) EXPECT_FALSE(d.reason.empty());
    PaintColour(&r, seed);
    absl::StatusOr<Detection> c = DetectBoxes(r.cloud, Options(true));
    ASSERT_TRUE(c.ok());
    Score(r, *c, &with_colour);
  }
  for (const auto& [name, c] :
       {std::pair{"corner only", corner_only}, std::pair{"corner + face", with_faces},
        std::pair{"corner + face + colour", with_colour}}) {
    std::cout << name << ": found " << c.found << "/" << c.pickable << ", correct " << c.correct
              << "/" << c.returned << ", top box wrong in " << c.top_wrong << "\n";
  }
  ASSERT_GT(with_faces.pickable, 20);
  EXPECT_GE(with_faces.found, corner_only.found);
  EXPECT_GE(with_colour.found, with_faces.found);
  EXPECT_GE(with_faces.correct, with_faces.returned - 1);
  EXPECT_GE(with_colour.correct, with_colour.returned - 1);
  EXPECT_EQ(with_faces.top_wrong, 0);
  EXPECT_EQ(with_colour.top_wrong, 0);
}

TEST(FaceDetectionTest, DepthOnlyFramesGiveTheSameBoxesWithColourIgnored) {
  // Colour is evidence, never a requirement: a grey image without any line
  // changes nothing.
  RenderedScene r = Render(MakeHeapScene(kCarton, 8, 3));
  absl::StatusOr<Detection> a = DetectBoxes(r.cloud, Options(true));
  r.cloud.rgb.assign(r.cloud.size(), 0x808080u);
  absl::StatusOr<Detection> b = DetectBoxes(r.cloud, Options(true));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->boxes.size(), b->boxes.size());
  for (size_t i = 0; i < a->boxes.size(); ++i) {
    EXPECT_TRUE(a->boxes[i].camera_T_box.isApprox(b->boxes[i].camera_T_box, 1e-9));
  }
}

TEST(FaceDetectionTest, MeasuredExtentIsReportedAndABoxOffNominalIsStillFound) {
  // The cartons are 1 cm longer than nominal (bulged): with a size
  // tolerance they are still found, and the measured extent says so.
  const BoxDims real{0.31, 0.20, 0.15};
  RenderedScene r = Render(MakeIsolatedScene(real, 2, 5));
  DetectorOptions o = Options(true);
  o.size_tolerance_m = 0.015;
  absl::StatusOr<Detection> det = DetectBoxes(r.cloud, o);
  ASSERT_TRUE(det.ok());
  ASSERT_FALSE(det->boxes.empty());
  bool measured = false;
  for (const DetectedBox& b : det->boxes) {
    for (double e : b.measured_extent_m) {
      if (e > 0.0) {
        measured = true;
        EXPECT_GT(e, 0.15);
        EXPECT_LT(e, 0.33);
      }
    }
  }
  EXPECT_TRUE(measured);
}

TEST(FaceDetectionTest, ABoxShortOfTheModelBothWaysIsASmallerBoxNotThisOne) {
  // Cartons 2 cm short of carton_s each way (0.28 x 0.18 m tops): within
  // the 2.5 cm a single axis may be off, but short on both, a smaller box.
  const BoxDims smaller{0.28, 0.18, 0.15};
  RenderedScene r = Render(MakeIsolatedScene(smaller, 2, 5));
  DetectorOptions o = Options(true);
  absl::StatusOr<Detection> det = DetectBoxes(r.cloud, o);
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_TRUE(det->boxes.empty());
  // The rule off, they pass as the box (what the rule is for).
  o.acceptance.max_short_both_axes_m = 0.0;
  det = DetectBoxes(r.cloud, o);
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_FALSE(det->boxes.empty());
}

// End to end on the active-stereo model (D4xx-like: seams filled in depth,
// fattened and flying outlines, an invalid band beside occluders) with its
// registered colour: isolated cartons are found, and on pallets of
// touching cartons (one layer, 0-2 mm gaps, boxes of another size among
// them) returned boxes are right and the top box is right.
TEST(StereoDetectionTest, IsolatedCartonsFoundAndTouchingPalletsGiveNoWrongBox) {
  SensorOptions sensor;
  sensor.kind = SensorKind::kStereo;
  sensor.color.enabled = true;
  absl::StatusOr<CameraIntrinsics> k = SensorIntrinsics(SensorKind::kStereo);
  ASSERT_TRUE(k.ok());
  const CameraPlacement place = SensorPlacement(SensorKind::kStereo, *k);
  Counts isolated, pallet;
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const RenderedScene a = Render(MakeIsolatedScene(kCarton, 2, seed, place), sensor);
    absl::StatusOr<Detection> da = DetectBoxes(a.cloud, Options(true));
    ASSERT_TRUE(da.ok());
    Score(a, *da, &isolated);
    const RenderedScene b = Render(
        MakeDistractorPalletScene(kCarton, 3, 3, 1, 0.001 * seed, 0, 1, seed, place), sensor);
    absl::StatusOr<Detection> db = DetectBoxes(b.cloud, Options(true));
    ASSERT_TRUE(db.ok());
    Score(b, *db, &pallet);
  }
  for (const auto& [name, c] :
       {std::pair{"stereo isolated", isolated}, std::pair{"stereo touching pallet", pallet}}) {
    std::cout << name << ": found " << c.found << "/" << c.pickable << ", correct " << c.correct
              << "/" << c.returned << ", top box wrong in " << c.top_wrong << "\n";
  }
  // Floors of where the detector stands (issue 15 aims higher: every
  // isolated box, no wrong box): 3/6 isolated, 20/24 on the pallets with one
  // wrong box in 21, the top box right in every frame.
  ASSERT_GE(isolated.pickable, 5);
  EXPECT_GE(isolated.found, 3);
  EXPECT_EQ(isolated.correct, isolated.returned);
  EXPECT_EQ(isolated.top_wrong, 0);
  ASSERT_GE(pallet.pickable, 15);
  EXPECT_GE(pallet.found, 18);
  EXPECT_GE(pallet.correct, pallet.returned - 1);
  EXPECT_EQ(pallet.top_wrong, 0);
}

TEST(GeometryParametersTest, SmallBoxesNearGetASmallerDiscAndCallerValuesStay) {
  DetectorOptions o;
  o.box = {0.05, 0.04, 0.03};
  DeriveGeometryParameters(0.6, 525.0, &o);
  EXPECT_NEAR(o.edge_points.radius_m, 0.0105, 1e-9);
  EXPECT_NEAR(o.segments.ransac_threshold_m, 0.00525, 1e-9);
  EXPECT_NEAR(o.clubbing.meet_distance_m, 0.00525, 1e-9);
  DetectorOptions c;
  c.box = {0.3, 0.2, 0.15};
  DeriveGeometryParameters(1.2, 525.0, &c);
  EXPECT_DOUBLE_EQ(c.edge_points.radius_m, 0.02);  // cartons at Kinect range: the paper's
  c.edge_points.radius_m = 0.03;
  DeriveGeometryParameters(3.0, 600.0, &c);
  EXPECT_DOUBLE_EQ(c.edge_points.radius_m, 0.03);  // the caller's value is kept
  DetectorOptions far;
  far.box = {0.4, 0.3, 0.25};
  DeriveGeometryParameters(3.0, 600.0, &far);
  EXPECT_NEAR(far.edge_points.radius_m, 0.03, 1e-9);  // 6 px at 3 m
}

TEST(GeometryParametersTest, ThePatchWindowWidensWhereTheBoxIsWideEnough) {
  // A carton's 15 cm side at 1.8 m (44 px) holds a 7 x 7-cell window (28 px)
  // within 0.8 of it; a brick's 5.7 cm at 1.5 m (20 px) does not.
  DetectorOptions carton;
  carton.box = {0.3, 0.2, 0.15};
  DeriveGeometryParameters(1.8, 525.0, &carton);
  EXPECT_EQ(carton.faces.patches.window_cells, 3);
  DetectorOptions brick;
  brick.box = {0.19, 0.09, 0.057};
  DeriveGeometryParameters(1.5, 525.0, &brick);
  EXPECT_EQ(brick.faces.patches.window_cells, 2);
  // Unknown depth, or a window the caller set: kept.
  DetectorOptions unknown;
  unknown.box = carton.box;
  DeriveGeometryParameters(0.0, 525.0, &unknown);
  EXPECT_EQ(unknown.faces.patches.window_cells, 2);
  DetectorOptions set;
  set.box = carton.box;
  set.faces.patches.window_cells = 1;
  DeriveGeometryParameters(1.8, 525.0, &set);
  EXPECT_EQ(set.faces.patches.window_cells, 1);
}

}  // namespace
}  // namespace cornerpose::testing
