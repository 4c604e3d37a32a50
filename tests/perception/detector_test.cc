// End-to-end tests: DetectBoxes with default options on rendered scenes with
// ground truth, and on malformed input.
#include "common/perception/detector.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/box/box_models.h"
#include "common/perception/box_pose.h"
#include "common/perception/internal/view_share.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

using ::testing::HasSubstr;

BoxDims Model(const std::string& name) {
  const absl::StatusOr<BoxDims> dims = BoxModelByName(name);
  EXPECT_TRUE(dims.ok()) << dims.status();
  return dims.value_or(BoxDims{0.3, 0.2, 0.15});
}

DetectorOptions Options(const BoxDims& dims) {
  DetectorOptions options;
  options.box = dims;
  return options;
}

// How far the box reaches below the floor, metres (0 when it does not).
double DepthBelowFloor(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims,
                       const Eigen::Vector4d& floor_plane_camera) {
  double below = 0.0;
  for (const Eigen::Vector3d& c : BoxCorners(camera_T_box, dims)) {
    below = std::max(below, -floor_plane_camera.dot(c.homogeneous()));
  }
  return below;
}

// A returned box that reaches this far into the floor cannot be a box: the
// signature of the known false positive (tests/perception/known_bugs_test.cc,
// NoWrongBoxOnIsolatedAndHeapScenes): a box stood on end on half of a real
// top face, sunk 10-15 cm into the floor. Metres.
constexpr double kSunkBelowFloorM = 0.02;

// How a detection compares with the ground truth of its scene.
struct Tally {
  int pickable = 0;   // pickable ground-truth boxes
  int found = 0;      // ... with a returned box within the "found" tolerance
  int displaced = 0;  // ... missed, with a sunk box (below) in their place
  int returned = 0;   // returned boxes
  int correct = 0;    // ... within the "correct" tolerance of some ground-truth box
  int sunk = 0;       // ... not correct, and reaching into the floor (the known bug)
  int wrong = 0;      // ... not correct otherwise
  std::vector<std::string> problems;

  void Add(const Tally& t) {
    pickable += t.pickable;
    found += t.found;
    displaced += t.displaced;
    returned += t.returned;
    correct += t.correct;
    sunk += t.sunk;
    wrong += t.wrong;
  }
  double recall() const { return pickable > 0 ? static_cast<double>(found) / pickable : 1.0; }
  double precision() const { return returned > 0 ? static_cast<double>(correct) / returned : 1.0; }
};

// The symmetry-aware pose error of the ground-truth box nearest to `pose`.
PoseError NearestError(const Eigen::Isometry3d& pose, const std::vector<GroundTruthBox>& truth,
                       const BoxDims& dims) {
  PoseError best{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (const GroundTruthBox& gt : truth) {
    const PoseError e = ComparePoses(pose, gt.camera_T_box, dims);
    if (e.translation_m < best.translation_m) best = e;
  }
  return best;
}

bool Within(const PoseError& e, double tol_m, double tol_deg) {
  return e.translation_m < tol_m && e.rotation_deg < tol_deg;
}

Tally Evaluate(const RenderedScene& out, const Detection& det, const BoxDims& dims, double found_m,
               double found_deg, double correct_m = 0.02, double correct_deg = 10.0) {
  Tally t;
  std::vector<Eigen::Vector3d> sunk_centres;
  for (size_t i = 0; i < det.boxes.size(); ++i) {
    ++t.returned;
    const Eigen::Isometry3d& pose = det.boxes[i].camera_T_box;
    const PoseError e = NearestError(pose, out.boxes, dims);
    if (Within(e, correct_m, correct_deg)) {
      ++t.correct;
      continue;
    }
    const double below = DepthBelowFloor(pose, dims, out.floor_plane_camera);
    std::ostringstream s;
    s << "returned box " << i << " (score " << det.boxes[i].score << ") is "
      << e.translation_m * 1000 << " mm, " << e.rotation_deg << " deg from any true box and "
      << below * 1000 << " mm below the floor";
    if (below > kSunkBelowFloorM) {
      ++t.sunk;
      sunk_centres.push_back(pose.translation());
      s << " (known bug)";
    } else {
      ++t.wrong;
    }
    t.problems.push_back(s.str());
  }
  for (size_t i = 0; i < out.boxes.size(); ++i) {
    const GroundTruthBox& gt = out.boxes[i];
    if (!gt.pickable) continue;
    ++t.pickable;
    PoseError best{std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity()};
    for (const DetectedBox& box : det.boxes) {
      const PoseError e = ComparePoses(box.camera_T_box, gt.camera_T_box, dims);
      if (Within(e, found_m, found_deg)) {
        best = e;
        break;
      }
      if (e.translation_m < best.translation_m) best = e;
    }
    if (Within(best, found_m, found_deg)) {
      ++t.found;
      continue;
    }
    std::ostringstream s;
    s << "pickable box " << i << " missed (nearest returned box " << best.translation_m * 1000
      << " mm, " << best.rotation_deg << " deg)";
    // A sunk box taking its place keeps the true one out (overlap test).
    const bool displaced =
        std::any_of(sunk_centres.begin(), sunk_centres.end(), [&](const Eigen::Vector3d& c) {
          return (c - gt.camera_T_box.translation()).norm() < std::max({dims.l, dims.b, dims.h});
        });
    if (displaced) {
      ++t.displaced;
      s << ", displaced by a sunk box (known bug)";
    }
    t.problems.push_back(s.str());
  }
  return t;
}

std::string Join(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "\n  " + l;
  return out;
}

// Properties every detection must have, right or wrong.
void ExpectWellFormed(const Detection& det, const BoxDims& dims) {
  for (size_t i = 0; i < det.boxes.size(); ++i) {
    const DetectedBox& b = det.boxes[i];
    EXPECT_GE(b.score, 0.0);
    EXPECT_LE(b.score, 1.0);
    if (i > 0) {
      EXPECT_LE(b.score, det.boxes[i - 1].score) << "boxes must be best first";
    }
    EXPECT_TRUE(b.camera_T_box.linear().isUnitary(1e-6));
    EXPECT_NEAR(b.camera_T_box.linear().determinant(), 1.0, 1e-6);
    EXPECT_GT(b.camera_T_box.translation().z(), 0.0);
    // The grasp face: its centre and normal agree with the pose, and it
    // looks at the camera.
    const Eigen::Vector3d n = b.camera_T_box.linear() * BoxFaceNormal(b.grasp_face);
    EXPECT_TRUE(b.grasp_normal_camera.isApprox(n, 1e-6));
    const double half = 0.5 * dims[static_cast<int>(b.grasp_face) / 2];
    EXPECT_TRUE(b.grasp_centre_camera.isApprox(
        b.camera_T_box * (BoxFaceNormal(b.grasp_face) * half), 1e-6));
    EXPECT_GT(b.grasp_normal_camera.dot(-b.grasp_centre_camera.normalized()), 0.0);
    EXPECT_GE(b.num_corners, 0);
    // Two returned boxes are two different boxes.
    for (size_t j = 0; j < i; ++j) {
      EXPECT_GT(TranslationErrorM(b.camera_T_box, det.boxes[j].camera_T_box),
                std::min({dims.l, dims.b, dims.h}) - 0.03)
          << "boxes " << j << " and " << i << " overlap";
    }
  }
  EXPECT_GE(det.timings.total_ms, 0.0);
}

void Report(const std::string& what, const Tally& t) {
  std::cout << what << ": found " << t.found << "/" << t.pickable << " pickable boxes ("
            << 100.0 * t.recall() << " %); " << t.correct << "/" << t.returned
            << " returned boxes correct (" << 100.0 * t.precision() << " %), " << t.sunk
            << " sunk into the floor (known bug, displacing " << t.displaced << " true boxes), "
            << t.wrong << " otherwise wrong\n";
  ::testing::Test::RecordProperty(what + "_found", t.found);
  ::testing::Test::RecordProperty(what + "_pickable", t.pickable);
  ::testing::Test::RecordProperty(what + "_correct", t.correct);
  ::testing::Test::RecordProperty(what + "_returned", t.returned);
  ::testing::Test::RecordProperty(what + "_sunk", t.sunk);
}

// Isolated boxes: three boxes lying flat, apart, all in view, seeds 1..8.
struct IsolatedCase {
  std::string model;
  // A pickable box is found within 10 mm and this many degrees.
  double found_deg;
  // Floors over all seeds.
  double min_recall;
  double min_precision;
  int max_sunk;
};

// Names the ctest test (gtest_discover_tests puts the printed parameter in
// place of the gtest index).
void PrintTo(const IsolatedCase& c, std::ostream* os) { *os << c.model; }

class IsolatedScenesTest : public ::testing::TestWithParam<IsolatedCase> {};

// Every pickable box is found and every returned box is right, in every
// scene; except for the known false positive (a box sunk into the floor,
// see kSunkBelowFloorM) and the true box it displaces, which are counted
// and held to the floors over all seeds instead.
TEST_P(IsolatedScenesTest, EveryPickableBoxIsFoundAndNoneIsWrong) {
  const IsolatedCase& c = GetParam();
  const BoxDims dims = Model(c.model);
  Tally total;
  for (uint32_t seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE(::testing::Message() << c.model << " seed " << seed);
    const RenderedScene out = Render(MakeIsolatedScene(dims, 3, seed), NoiseOptions{});
    const absl::StatusOr<Detection> det = DetectBoxes(out.cloud, Options(dims));
    ASSERT_TRUE(det.ok()) << det.status();
    ExpectWellFormed(*det, dims);
    const Tally t = Evaluate(out, *det, dims, 0.010, c.found_deg);
    total.Add(t);
    ASSERT_EQ(t.pickable, 3);
    // A miss is held to the recall floor below; a wrong box fails here.
    if (t.found + t.displaced < t.pickable) std::cout << Join(t.problems) << "\n";
    EXPECT_EQ(t.correct + t.sunk, t.returned) << Join(t.problems);
    EXPECT_EQ(t.wrong, 0);
  }
  Report("isolated_" + c.model, total);
  EXPECT_GE(total.recall(), c.min_recall);
  EXPECT_GE(total.precision(), c.min_precision);
  EXPECT_LE(total.sunk, c.max_sunk);
}

// Achieved now, seeds 1-8: carton_s 24/24 found, 24/24 correct; brick
// 23/24 found (seed 6: a short side lost to a stray segment), 23/23
// correct, none sunk. Earlier (fcd3206-7daebbf) 1-2 boxes per model sank
// into the floor; the floors below allow a miss, never a wrong box. A
// brick's top face is 9 cm wide and its turn is less sure: seed 2 finds one
// 1 mm off but 6.2 degrees turned, so bricks count as found within 7
// degrees.
INSTANTIATE_TEST_SUITE_P(Models, IsolatedScenesTest,
                         ::testing::Values(IsolatedCase{"carton_s", 5.0, 0.95, 0.95, 1},
                                           IsolatedCase{"brick", 7.0, 0.9, 0.95, 1}));

TEST(HeapScenesTest, MostPickableBoxesAreFoundAndFewReturnedBoxesAreWrong) {
  const BoxDims dims = Model("carton_s");
  Tally total;
  for (uint32_t seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const RenderedScene out = Render(MakeHeapScene(dims, 10, seed), NoiseOptions{});
    const absl::StatusOr<Detection> det = DetectBoxes(out.cloud, Options(dims));
    ASSERT_TRUE(det.ok()) << det.status();
    ExpectWellFormed(*det, dims);
    const Tally t = Evaluate(out, *det, dims, 0.020, 10.0);
    std::cout << "heap seed " << seed << ": found " << t.found << "/" << t.pickable << ", correct "
              << t.correct << "/" << t.returned << Join(t.problems) << "\n";
    total.Add(t);
  }
  Report("heap_carton_s", total);
  // Achieved, seeds 1-10: 44/68 found (65 %), 46/47 returned boxes correct
  // (the other one sunk into the floor). Earlier (fcd3206-7daebbf) 51-52/68
  // found but 54/55 correct: later checks traded recall here for
  // precision on the dev set and pallets.
  ASSERT_GT(total.pickable, 50);
  EXPECT_GE(total.recall(), 0.6);
  EXPECT_GE(total.precision(), 0.90);
  EXPECT_LE(total.wrong, 1);
}

// Bricks in a heap show their long sides as edges more often than a
// corner: the faces between parallel edges (DetectorOptions::edge_pairs)
// find boxes the corners and the planar patches miss, and no wrong one.
TEST(HeapScenesTest, FacesBetweenParallelEdgesFindMoreBricks) {
  const BoxDims dims = Model("brick");
  Tally without, with;
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const RenderedScene out = Render(MakeHeapScene(dims, 8, seed), NoiseOptions{});
    DetectorOptions options = Options(dims);
    options.edge_pairs.enabled = false;
    const absl::StatusOr<Detection> off = DetectBoxes(out.cloud, options);
    options.edge_pairs.enabled = true;
    const absl::StatusOr<Detection> on = DetectBoxes(out.cloud, options);
    ASSERT_TRUE(off.ok()) << off.status();
    ASSERT_TRUE(on.ok()) << on.status();
    ExpectWellFormed(*on, dims);
    const Tally t_off = Evaluate(out, *off, dims, 0.020, 10.0);
    const Tally t_on = Evaluate(out, *on, dims, 0.020, 10.0);
    std::cout << "brick heap seed " << seed << ": found " << t_off.found << " -> " << t_on.found
              << " of " << t_on.pickable << ", wrong " << t_off.wrong << " -> " << t_on.wrong
              << Join(t_on.problems) << "\n";
    without.Add(t_off);
    with.Add(t_on);
  }
  EXPECT_GT(with.found, without.found);
  EXPECT_LE(with.wrong + with.sunk, without.wrong + without.sunk);
}

// Face proposals lying on the floor found are not judged
// (DetectorOptions::judge_faces_on_floor false): fewer hypotheses refined,
// the same boxes. Bricks lying flat on an active stereo camera's noisy
// floor: the floor's seam lines frame brick faces on it, each box 5.7 cm
// through the floor, within what a refinement could move (so the judge's
// own check before refining leaves them).
TEST(DetectorTest, FaceProposalsOnTheFloorAreNotJudgedAndChangeNoBox) {
  const BoxDims dims = Model("brick");
  const CameraIntrinsics stereo = *SensorIntrinsics(SensorKind::kStereo);
  SensorOptions sensor;
  sensor.kind = SensorKind::kStereo;
  sensor.color.enabled = true;
  int refined_without = 0, refined_with = 0;
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const RenderedScene out = Render(
        MakeIsolatedScene(dims, 3, seed, SensorPlacement(SensorKind::kStereo, stereo)), sensor);
    DetectorOptions options = Options(dims);
    options.judge_faces_on_floor = true;
    const absl::StatusOr<Detection> judged = DetectBoxes(out.cloud, options);
    options.judge_faces_on_floor = false;
    const absl::StatusOr<Detection> skipped = DetectBoxes(out.cloud, options);
    ASSERT_TRUE(judged.ok()) << judged.status();
    ASSERT_TRUE(skipped.ok()) << skipped.status();
    ASSERT_EQ(skipped->boxes.size(), judged->boxes.size());
    for (size_t i = 0; i < judged->boxes.size(); ++i) {
      EXPECT_TRUE(skipped->boxes[i].camera_T_box.isApprox(judged->boxes[i].camera_T_box, 1e-9));
    }
    refined_with += judged->hypotheses.refined;
    refined_without += skipped->hypotheses.refined;
  }
  std::cout << "refined with the floor's faces " << refined_with << ", without " << refined_without
            << "\n";
  EXPECT_LT(refined_without, refined_with);
}

TEST(DetectorTest, UnorganizedCloudOfAFrameFindsTheSameBoxes) {
  const BoxDims dims = Model("carton_s");
  const RenderedScene out = Render(MakeIsolatedScene(dims, 3, 1), NoiseOptions{});
  PointCloud cloud;
  for (const Eigen::Vector3f& p : out.cloud.xyz) {
    if (PointCloud::IsValid(p)) cloud.xyz.push_back(p);
  }
  std::mt19937 rng(21);
  std::shuffle(cloud.xyz.begin(), cloud.xyz.end(), rng);
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  DetectorOptions options = Options(dims);
  options.camera = out.camera;
  const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
  ASSERT_TRUE(det.ok()) << det.status();
  ExpectWellFormed(*det, dims);
  const Tally t = Evaluate(out, *det, dims, 0.010, 5.0);
  EXPECT_EQ(t.found, 3) << Join(t.problems);
  EXPECT_EQ(t.correct, t.returned) << Join(t.problems);
}

// Two cartons lying flat, one in the middle of the view and one with a
// quarter of its length past the image's right edge: both are returned, and
// the one partly out of view ranks second, its score scaled by its share in
// view (DetectorOptions::score_in_view); which boxes are returned does not
// change.
TEST(DetectorTest, ABoxPartlyOutOfViewRanksBelowOneInView) {
  const BoxDims dims = Model("carton_s");
  Scene scene;
  scene.world_T_camera = LookAtCamera({0.0, 0.0, 0.0}, 1.3, 0.0, 0.0, 0.0);
  const double half_width = (scene.camera.width / 2.0) / scene.camera.fx * (1.3 - dims.h);
  for (const double x : {-0.1, half_width + 0.075 - dims.l / 2.0}) {
    SceneBox box;
    box.dims = dims;
    box.world_T_box.translation() = Eigen::Vector3d(x, 0.0, dims.h / 2.0);
    scene.boxes.push_back(box);
  }
  const RenderedScene out = Render(scene, NoiseOptions{});
  DetectorOptions plain = Options(dims);
  plain.score_in_view = false;
  const absl::StatusOr<Detection> a = DetectBoxes(out.cloud, plain);
  const absl::StatusOr<Detection> b = DetectBoxes(out.cloud, Options(dims));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->boxes.size(), 2u);
  ASSERT_EQ(b->boxes.size(), 2u);
  const Tally t = Evaluate(out, *b, dims, 0.010, 5.0);
  EXPECT_EQ(t.correct, 2) << Join(t.problems);
  // b's first box is the one in view; scores are a's times the share in view.
  const Eigen::Vector3d in_view = out.boxes[0].camera_T_box.translation();
  EXPECT_LT((b->boxes[0].camera_T_box.translation() - in_view).norm(), 0.02);
  EXPECT_GT((b->boxes[1].camera_T_box.translation() - in_view).norm(), 0.2);
  for (const DetectedBox& box : b->boxes) {
    const auto same = std::find_if(a->boxes.begin(), a->boxes.end(), [&](const DetectedBox& o) {
      return o.camera_T_box.isApprox(box.camera_T_box, 1e-12);
    });
    ASSERT_NE(same, a->boxes.end());
    const double share = internal::BoxViewShare(out.camera, box.camera_T_box, dims);
    EXPECT_NEAR(box.score, same->score * share, 1e-6);  // its camera is fitted to the cloud
  }
  EXPECT_DOUBLE_EQ(internal::BoxViewShare(out.camera, b->boxes[0].camera_T_box, dims), 1.0);
  const double edge_share = internal::BoxViewShare(out.camera, b->boxes[1].camera_T_box, dims);
  EXPECT_GT(edge_share, 0.6);
  EXPECT_LT(edge_share, 0.9);
}

TEST(DetectorTest, SameInputSameOutputWithAnyThreadCount) {
  const BoxDims dims = Model("carton_s");
  const RenderedScene out = Render(MakeHeapScene(dims, 6, 3), NoiseOptions{});
  DetectorOptions one = Options(dims);
  one.num_threads = 1;
  DetectorOptions two = Options(dims);
  two.num_threads = 2;
  const absl::StatusOr<Detection> a = DetectBoxes(out.cloud, one);
  const absl::StatusOr<Detection> b = DetectBoxes(out.cloud, two);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_FALSE(a->boxes.empty());
  EXPECT_EQ(a->edge_points.size(), b->edge_points.size());
  EXPECT_EQ(a->segments.size(), b->segments.size());
  ASSERT_EQ(a->boxes.size(), b->boxes.size());
  for (size_t i = 0; i < a->boxes.size(); ++i) {
    EXPECT_TRUE(a->boxes[i].camera_T_box.isApprox(b->boxes[i].camera_T_box, 1e-12));
    EXPECT_EQ(a->boxes[i].score, b->boxes[i].score);
  }
}

TEST(DetectorBadInputTest, EmptyCloudGivesNoBoxes) {
  const absl::StatusOr<Detection> det = DetectBoxes(PointCloud{}, Options(Model("carton_s")));
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_TRUE(det->boxes.empty());
  EXPECT_TRUE(det->edge_points.empty());
}

TEST(DetectorBadInputTest, AllNanFrameGivesNoBoxes) {
  PointCloud cloud;
  cloud.width = 640;
  cloud.height = 480;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.xyz.assign(640 * 480, Eigen::Vector3f(nan, nan, nan));
  const absl::StatusOr<Detection> det = DetectBoxes(cloud, Options(Model("carton_s")));
  ASSERT_TRUE(det.ok()) << det.status();
  EXPECT_TRUE(det->boxes.empty());
}

TEST(DetectorBadInputTest, FloorOnlyGivesNoBoxes) {
  for (uint32_t seed : {1u, 2u}) {
    Scene scene = MakeIsolatedScene(Model("carton_s"), 1, seed);  // for its camera
    scene.boxes.clear();
    const RenderedScene out = Render(scene, NoiseOptions{});
    ASSERT_GT(out.stats.valid, 200000);
    for (const std::string model : {"carton_s", "brick"}) {
      const absl::StatusOr<Detection> det = DetectBoxes(out.cloud, Options(Model(model)));
      ASSERT_TRUE(det.ok()) << det.status();
      EXPECT_TRUE(det->boxes.empty()) << model << " seed " << seed;
    }
  }
}

TEST(DetectorBadInputTest, NonPositiveBoxSizeNamesTheSide) {
  const PointCloud empty;
  struct Case {
    BoxDims dims;
    const char* side;
  };
  for (const Case& c :
       {Case{{0.0, 0.2, 0.15}, "l="}, Case{{0.3, -0.2, 0.15}, "b="}, Case{{0.3, 0.2, 0.0}, "h="},
        Case{{0.3, 0.2, std::numeric_limits<double>::quiet_NaN()}, "h="}}) {
    const absl::StatusOr<Detection> det = DetectBoxes(empty, Options(c.dims));
    EXPECT_EQ(det.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(det.status().message()), HasSubstr(c.side));
  }
  // No size at all (the default BoxDims) is refused too.
  EXPECT_EQ(DetectBoxes(empty, DetectorOptions{}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(DetectorBadInputTest, AbsurdOptionsAreInvalidArgument) {
  const PointCloud empty;
  DetectorOptions options = Options(Model("carton_s"));
  options.edge_points.radius_m = 5.0;
  absl::StatusOr<Detection> det = DetectBoxes(empty, options);
  EXPECT_EQ(det.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(det.status().message()), HasSubstr("radius"));

  options = Options(Model("carton_s"));
  options.edge_points.radius_m = 0.0;
  EXPECT_EQ(DetectBoxes(empty, options).status().code(), absl::StatusCode::kInvalidArgument);
  options = Options(Model("carton_s"));
  options.num_threads = 0;
  EXPECT_EQ(DetectBoxes(empty, options).status().code(), absl::StatusCode::kInvalidArgument);
  options = Options(Model("carton_s"));
  options.segments.ransac_threshold_m = 0.0;
  EXPECT_EQ(DetectBoxes(empty, options).status().code(), absl::StatusCode::kInvalidArgument);
  options = Options(Model("carton_s"));
  options.acceptance.min_support = 2.0;
  EXPECT_EQ(DetectBoxes(empty, options).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(DetectorBadInputTest, MalformedCloudIsInvalidArgument) {
  PointCloud cloud;
  cloud.width = 640;
  cloud.height = 480;
  cloud.xyz.assign(1000, Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(DetectBoxes(cloud, Options(Model("carton_s"))).status().code(),
            absl::StatusCode::kInvalidArgument);
  cloud.width = 1000;
  cloud.height = 1;
  DetectorOptions options = Options(Model("carton_s"));
  options.max_points = 999;
  EXPECT_EQ(DetectBoxes(cloud, options).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(DetectorBadInputTest, NanAndInfMixedCoordinatesDoNotCrash) {
  const BoxDims dims = Model("carton_s");
  const RenderedScene out = Render(MakeIsolatedScene(dims, 3, 1), NoiseOptions{});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::mt19937 rng(13);
  auto corrupt = [&](PointCloud* cloud, int n) {
    std::uniform_int_distribution<size_t> pick(0, cloud->size() - 1);
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3f& p = cloud->xyz[pick(rng)];
      switch (i % 7) {
        case 0:
          p.x() = nan;
          break;
        case 1:
          p.y() = inf;
          break;
        case 2:
          p.z() = nan;
          break;
        case 3:
          p.z() = inf;
          break;
        case 4:
          p.x() = -inf;
          break;
        case 5:
          p.z() = -1.0f;
          break;
        default:
          p = Eigen::Vector3f(inf, -inf, nan);
          break;
      }
    }
  };
  // Organized, a few and many corrupted pixels.
  for (int n : {7, 2000}) {
    PointCloud cloud = out.cloud;
    corrupt(&cloud, n);
    const absl::StatusOr<Detection> det = DetectBoxes(cloud, Options(dims));
    ASSERT_TRUE(det.ok()) << det.status();
    ExpectWellFormed(*det, dims);
    // Whatever it returns is right.
    EXPECT_EQ(Evaluate(out, *det, dims, 0.01, 5.0).correct, static_cast<int>(det->boxes.size()));
  }
  // Unorganized.
  PointCloud cloud;
  for (const Eigen::Vector3f& p : out.cloud.xyz) {
    if (PointCloud::IsValid(p)) cloud.xyz.push_back(p);
  }
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  corrupt(&cloud, 2000);
  DetectorOptions options = Options(dims);
  options.camera = out.camera;
  const absl::StatusOr<Detection> det = DetectBoxes(cloud, options);
  ASSERT_TRUE(det.ok()) << det.status();
  ExpectWellFormed(*det, dims);
  const Tally t = Evaluate(out, *det, dims, 0.01, 5.0);
  EXPECT_EQ(t.correct, t.returned) << Join(t.problems);
  EXPECT_EQ(t.found, 3) << Join(t.problems);
}

}  // namespace
}  // namespace cornerpose::testing
