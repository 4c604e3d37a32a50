// Refinement on the grasp face (RefineOnGraspFace): a hypothesis is moved
// onto the measured face, and each side of the face is read as free, a seam
// to a touching box, running on (a bigger face) or hidden under a box
// standing on it. Scenes from the test generator with exact depth, so what
// is tested is the geometry, not the noise models.
#include "common/perception/box_refinement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/perception/camera_model.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};

// Boxes lying flat on the floor (x along l), seen from `distance_m` above
// the first one, the camera tilted and turned so that no side lines up with
// the pixel grid.
struct FlatScene {
  RenderedScene rendered;
  DepthImage depth;
};

// The scene rendered with exact depth, and its depth image.
FlatScene RenderExact(const Scene& scene) {
  NoiseOptions exact;
  exact.enabled = false;
  FlatScene s;
  s.rendered = Render(scene, exact);
  s.depth = MakeDepthImage(s.rendered.cloud, s.rendered.camera);
  return s;
}

FlatScene RenderFlat(const std::vector<SceneBox>& boxes, double distance_m = 1.1) {
  Scene scene;
  scene.camera = CameraIntrinsics{};
  scene.world_T_camera =
      LookAtCamera(boxes.front().world_T_box.translation(), distance_m, 8.0, 25.0, 0.0);
  scene.boxes = boxes;
  return RenderExact(scene);
}

SceneBox Flat(const BoxDims& dims, double x, double y, double z_bottom = 0.0) {
  SceneBox b;
  b.dims = dims;
  b.world_T_box.translation() = Eigen::Vector3d(x, y, z_bottom + dims.h / 2.0);
  return b;
}

// The box's pose in the camera moved by (da, db) metres along its own x and
// y axes and turned by yaw_deg about its z axis.
Eigen::Isometry3d Moved(const Eigen::Isometry3d& camera_T_box, double dx, double dy,
                        double yaw_deg) {
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.translation() = Eigen::Vector3d(dx, dy, 0.0);
  delta.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  return camera_T_box * delta;
}

// The top face (world +z) in the box frame the generator uses.
BoxFace TopFace(const GroundTruthBox& gt) { return gt.grasp_face; }

TEST(RefineOnGraspFaceTest, AnIsolatedBoxComesBackFromAnOffsetReadingWithFourFreeSides) {
  const FlatScene s = RenderFlat({Flat(kCartonS, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  for (const auto& [dx, dy, yaw] :
       {std::tuple{0.0, 0.0, 0.0}, std::tuple{0.015, -0.01, 4.0}, std::tuple{-0.02, 0.012, -6.0}}) {
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, dx, dy, yaw);
    const RefinementResult r =
        RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
    ASSERT_TRUE(r.ok) << dx << " " << dy << " " << yaw;
    const PoseError e = ComparePoses(pose, gt.camera_T_box, kCartonS);
    EXPECT_LT(e.translation_m, 0.003) << dx << " " << dy << " " << yaw;
    EXPECT_LT(e.rotation_deg, 1.0) << dx << " " << dy << " " << yaw;
    EXPECT_EQ(r.free_sides, 4);
    for (SideKind k : r.sides) EXPECT_EQ(k, SideKind::kFree);
    // The face measured between its free sides: l and b of the box.
    EXPECT_NEAR(std::max(r.extent_a_m, r.extent_b_m), kCartonS.l, 0.008);
    EXPECT_NEAR(std::min(r.extent_a_m, r.extent_b_m), kCartonS.b, 0.008);
    EXPECT_LT(r.plane_rms_m, 0.001);
  }
}

// 8 cm along the box (the band a side is looked for in is 2 cm): the near
// side finds the face running on, the far one nothing to measure, and the
// reading does not move: it is not confirmed as this box.
TEST(RefineOnGraspFaceTest, AReadingFarOffIsNotMeasuredAsTheBox) {
  const FlatScene s = RenderFlat({Flat(kCartonS, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.08, 0.0, 0.0);
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  EXPECT_EQ(r.sides[0], SideKind::kUnknown);
  EXPECT_EQ(r.sides[1], SideKind::kContinues);
  EXPECT_EQ(r.extent_a_m, 0.0) << "no free side pair along the box";
  EXPECT_GT(ComparePoses(pose, gt.camera_T_box, kCartonS).translation_m, 0.07);
}

// Two cartons end to end with a 3 mm gap: the sides facing each other are
// seams, the others free.
TEST(RefineOnGraspFaceTest, TouchingCartonsMeetAtASeam) {
  const FlatScene s =
      RenderFlat({Flat(kCartonS, 0.0, 0.0), Flat(kCartonS, kCartonS.l + 0.003, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.006, 0.004, 1.0);
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  ASSERT_TRUE(r.ok);
  int seams = 0, free = 0;
  for (SideKind k : r.sides) {
    seams += k == SideKind::kSeam;
    free += k == SideKind::kFree;
  }
  EXPECT_EQ(seams, 1);
  EXPECT_EQ(free, 3);
  const PoseError e = ComparePoses(pose, gt.camera_T_box, kCartonS);
  EXPECT_LT(e.translation_m, 0.004);
  EXPECT_LT(e.rotation_deg, 1.0);
}

// A carton in the middle of a 3 x 3 block with 3 mm gaps: seams on all four
// sides, no free one. Its turn comes from where each half of its long
// sides has the seam (RefinementOptions::seam_turn_min_length_m): a
// reading turned by 3 degrees comes back square; with seams giving a
// position only, it keeps the turn.
TEST(RefineOnGraspFaceTest, SeamsAlongLongSidesTurnTheFace) {
  std::vector<SceneBox> boxes;
  for (int row = -1; row <= 1; ++row) {
    for (int col = -1; col <= 1; ++col) {
      boxes.push_back(Flat(kCartonS, col * (kCartonS.l + 0.003), row * (kCartonS.b + 0.003)));
    }
  }
  std::swap(boxes[0], boxes[4]);  // the middle one first: the camera looks at it
  const FlatScene s = RenderFlat(boxes, 1.3);
  const GroundTruthBox& gt = s.rendered.boxes[0];
  auto refine = [&](double seam_turn) {
    RefinementOptions o;
    o.seam_turn_min_length_m = seam_turn;
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.002, 0.002, 3.0);
    const RefinementResult r = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), o, &pose);
    EXPECT_TRUE(r.ok);
    if (seam_turn > 0.0) EXPECT_EQ(std::count(r.sides.begin(), r.sides.end(), SideKind::kSeam), 4);
    return ComparePoses(pose, gt.camera_T_box, kCartonS);
  };
  const PoseError turned = refine(0.1);
  EXPECT_LT(turned.rotation_deg, 1.0);
  EXPECT_LT(turned.translation_m, 0.003);
  EXPECT_GT(refine(0.0).rotation_deg, 2.5) << "seams give a position only";
}

// With a colour image, a groove in the depth is a seam only where an image
// line runs along it (RefinementOptions::colour_confirms_seam): the same
// 3 mm gap is a seam when the image shows the gap darker than the cartons,
// and the face runs on there when the image is one even grey (a stereo
// camera's noise leaves such grooves inside faces); without the rule, or
// when the image does not even show the cartons' outline, the depth alone
// decides.
TEST(RefineOnGraspFaceTest, ADepthSeamNeedsALineInTheColourImage) {
  FlatScene s = RenderFlat({Flat(kCartonS, 0.0, 0.0), Flat(kCartonS, kCartonS.l + 0.003, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  const int w = s.depth.camera.width, h = s.depth.camera.height;
  const Eigen::Isometry3d box_T_camera = gt.camera_T_box.inverse();
  auto sides_with = [&](bool dark_gap, double confirm) {
    // The cartons' tops a lighter grey than the floor (the image shows their
    // outline) and, with `dark_gap`, the gap's shadow a dark line 6 mm wide
    // along it, as a colour camera sees two cartons meet.
    s.depth.grey.assign(static_cast<size_t>(w) * h, 90.0f);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const float z = s.depth.at(u, v);
        if (std::isnan(z)) continue;
        const Eigen::Vector3d p = box_T_camera * (z * PixelRay(s.depth.camera, u, v));
        float& g = s.depth.grey[static_cast<size_t>(v) * w + u];
        if (p.z() > 0.0) g = 150.0f;
        if (dark_gap && std::abs(p.x() - (kCartonS.l / 2 + 0.0015)) < 0.003) g = 60.0f;
      }
    }
    RefinementOptions options;
    options.colour_confirms_seam = confirm;
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.006, 0.004, 1.0);
    const RefinementResult r = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), options, &pose);
    int seams = 0, runs_on = 0;
    for (SideKind k : r.sides) {
      seams += k == SideKind::kSeam;
      runs_on += k == SideKind::kContinues;
    }
    return std::pair{seams, runs_on};
  };
  EXPECT_EQ(sides_with(/*dark_gap=*/true, 0.3), std::pair(1, 0));
  EXPECT_EQ(sides_with(/*dark_gap=*/false, 0.3), std::pair(0, 1));
  EXPECT_EQ(sides_with(/*dark_gap=*/false, 0.0), std::pair(1, 0));
  // An image that shows nothing (one grey everywhere, or not registered) is
  // no evidence against a seam.
  s.depth.grey.assign(static_cast<size_t>(w) * h, 128.0f);
  Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.006, 0.004, 1.0);
  const RefinementResult blank =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  EXPECT_EQ(std::count(blank.sides.begin(), blank.sides.end(), SideKind::kSeam), 1);
}

// Two cartons end to end with no gap at all leave nothing in exact depth:
// the face runs on. A gap finer than a pixel shows as a sparse line of
// missing returns along the seam (here every third pixel within 0.75 mm of
// it returns nothing): a seam (RefinementOptions::sparse_seam_missing),
// unless the test is off. The same number of missing returns scattered over
// the face is no seam.
TEST(RefineOnGraspFaceTest, AGapFinerThanAPixelShowsAsASparseLineOfMissingReturns) {
  const FlatScene clean = RenderFlat({Flat(kCartonS, 0.0, 0.0), Flat(kCartonS, kCartonS.l, 0.0)});
  const GroundTruthBox& gt = clean.rendered.boxes[0];
  const Eigen::Isometry3d box_T_camera = gt.camera_T_box.inverse();
  const int w = clean.depth.camera.width, h = clean.depth.camera.height;
  // Pixels on the two tops near the seam line (box x = l / 2), in order.
  std::vector<size_t> on_line, on_tops;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = clean.depth.at(u, v);
      if (std::isnan(z)) continue;
      const Eigen::Vector3d p = box_T_camera * (z * PixelRay(clean.depth.camera, u, v));
      if (p.z() < kCartonS.h / 2 - 0.002 || std::abs(p.y()) > kCartonS.b / 2 - 0.01) continue;
      const size_t i = static_cast<size_t>(v) * w + u;
      if (std::abs(p.x() - kCartonS.l / 2) < 0.00075) on_line.push_back(i);
      if (std::abs(p.x()) < kCartonS.l / 2 - 0.03) on_tops.push_back(i);
    }
  }
  ASSERT_GT(on_line.size(), 60u);
  auto seams = [&](const std::vector<size_t>& drop, double sparse) {
    DepthImage depth = clean.depth;
    for (size_t i : drop) depth.z[i] = std::numeric_limits<float>::quiet_NaN();
    RefinementOptions options;
    options.sparse_seam_missing = sparse;
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.003, 0.002, 0.5);
    const RefinementResult r = RefineOnGraspFace(depth, kCartonS, TopFace(gt), options, &pose);
    EXPECT_TRUE(r.ok);
    return std::count(r.sides.begin(), r.sides.end(), SideKind::kSeam);
  };
  std::vector<size_t> line_drop, scattered;
  for (size_t k = 0; k < on_line.size(); k += 3) line_drop.push_back(on_line[k]);
  const size_t every = on_tops.size() / line_drop.size();
  for (size_t k = 0; k < on_tops.size() && scattered.size() < line_drop.size(); k += every) {
    scattered.push_back(on_tops[k]);
  }
  EXPECT_EQ(seams({}, 0.05), 0) << "no gap, no seam";
  EXPECT_EQ(seams(line_drop, 0.05), 1) << "a sparse line of missing returns";
  EXPECT_EQ(seams(line_drop, 0.0), 0) << "the test off";
  EXPECT_EQ(seams(scattered, 0.05), 0) << "as many misses, scattered";
}

// A layer of touching cartons tiles whole, but a reading slid along a row
// between two sides where the face runs on (no gap to see) is not one of
// its tiles: past each such side the layer must run on a whole number of
// cartons. Two rows of three, end to end with no gap, the rows 3 mm apart
// (a seam on the reading's +b side).
TEST(RefineOnGraspFaceTest, AReadingSlidAlongARowIsNotATile) {
  std::vector<SceneBox> boxes;
  for (int row = 0; row < 2; ++row) {
    for (int col = -1; col <= 1; ++col) {
      boxes.push_back(Flat(kCartonS, col * kCartonS.l, row * (kCartonS.b + 0.003)));
    }
  }
  const FlatScene s = RenderFlat(boxes, 1.3);
  const GroundTruthBox& gt = s.rendered.boxes[1];  // row 0, the middle one
  auto sides = [&](double slide) {
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, slide, 0.0, 0.0);
    const RefinementResult r =
        RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
    EXPECT_TRUE(r.ok) << slide;
    return std::pair{r.sides[0], r.sides[1]};
  };
  EXPECT_EQ(sides(0.0), std::pair(SideKind::kTiled, SideKind::kTiled));
  EXPECT_EQ(sides(0.04), std::pair(SideKind::kContinues, SideKind::kContinues));
}

// A carton-sized reading on one end of a face twice as long: the side
// toward the rest of the face runs on flat.
TEST(RefineOnGraspFaceTest, AReadingOnPartOfABiggerFaceRunsOn) {
  const BoxDims long_box{2 * kCartonS.l, kCartonS.b, kCartonS.h};
  const FlatScene s = RenderFlat({Flat(long_box, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  // The carton at the long box's -x end, its top on the long box's top.
  Eigen::Isometry3d pose = Moved(gt.camera_T_box, -kCartonS.l / 2.0, 0.0, 0.0);
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  int runs_on = 0;
  for (SideKind k : r.sides) runs_on += k == SideKind::kContinues;
  EXPECT_EQ(runs_on, 1);
}

// The same reading, refined as the detector does: its first step already
// shows the side running on flat, with no seam anywhere, having barely
// moved it, so the refinement ends there (what a second step would read is
// the same side on flat). Started 1 cm off across the face, the first step
// moves it back by that much and every step runs.
TEST(RefineOnGraspFaceTest, AReadingOnABiggerFaceEndsAfterItsFirstStep) {
  const BoxDims long_box{2 * kCartonS.l, kCartonS.b, kCartonS.h};
  const FlatScene s = RenderFlat({Flat(long_box, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  RefinementOptions one_step, every_step;
  one_step.iterations = 1;
  every_step.end_on_flat_shift_m = 0.0;
  auto refine = [&](double across, const RefinementOptions& o) {
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, -kCartonS.l / 2.0, across, 0.0);
    const RefinementResult r = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), o, &pose);
    EXPECT_TRUE(r.ok);
    return std::pair{r, pose};
  };
  const auto [ended, ended_pose] = refine(0.0, RefinementOptions{});
  const auto [first, first_pose] = refine(0.0, one_step);
  EXPECT_EQ(ended.sides, first.sides);
  EXPECT_TRUE(ended_pose.isApprox(first_pose, 0.0)) << "the first step's pose, bit for bit";
  EXPECT_EQ(std::count(ended.sides.begin(), ended.sides.end(), SideKind::kContinues), 1);
  const auto [full, full_pose] = refine(0.0, every_step);
  EXPECT_EQ(full.sides, ended.sides) << "a second step reads the same";
  EXPECT_FALSE(full_pose.isApprox(first_pose, 0.0)) << "... from a pose a little moved";

  const auto [slid, slid_pose] = refine(0.01, RefinementOptions{});
  const auto [slid_full, slid_full_pose] = refine(0.01, every_step);
  EXPECT_EQ(slid.sides, slid_full.sides);
  EXPECT_TRUE(slid_pose.isApprox(slid_full_pose, 0.0)) << "moved 1 cm: every step ran";
  EXPECT_FALSE(slid_pose.isApprox(refine(0.01, one_step).second, 1e-12));
}

// A face read 5 cm wider than the carton's top (a box of 0.30 x 0.25
// placed on a 0.30 x 0.20 top, its -b side on the carton's): just inside
// its +b side the pixels see the floor, behind the plane: the side is
// unknown (no point on the plane there) and seen through. With the share 0
// the rule is off; a side with nothing behind it (the true top's) is not.
TEST(RefineOnGraspFaceTest, ASideWhereThePixelsSeeBehindThePlaneIsSeenThrough) {
  const FlatScene s = RenderFlat({Flat(kCartonS, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  const BoxDims wide{0.30, 0.25, 0.15};
  for (const double share : {0.4, 0.0}) {
    RefinementOptions o;
    o.seen_through_share = share;
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.0, 0.025, 0.0);
    const RefinementResult r = RefineOnGraspFace(s.depth, wide, TopFace(gt), o, &pose);
    ASSERT_TRUE(r.ok) << share;
    int unknown = -1;
    for (int i = 0; i < 4; ++i) {
      if (r.sides[i] == SideKind::kUnknown) unknown = i;
    }
    ASSERT_GE(unknown, 2) << "a side along the box's x, unseen";
    EXPECT_EQ(r.seen_through[unknown], share > 0.0) << share;
    for (int i = 0; i < 4; ++i) {
      if (i != unknown) EXPECT_FALSE(r.seen_through[i]) << i;
    }
  }
  // The carton read as itself: no side seen through.
  Eigen::Isometry3d pose = gt.camera_T_box;
  const RefinementResult r = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), {}, &pose);
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(r.seen_through[i]) << i;
}

TEST(RefinementOptionsTest, ValidateNamesTheNewFields) {
  RefinementOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.end_on_flat_shift_m = -0.001;
  EXPECT_NE(o.Validate().message().find("end_on_flat_shift_m"), std::string::npos);
  o.end_on_flat_shift_m = 0.0;
  EXPECT_TRUE(o.Validate().ok()) << "0: every step";
  o.seam_turn_max_deg = 90.0;
  EXPECT_NE(o.Validate().message().find("seam_turn_max_deg"), std::string::npos);
  o.seam_turn_max_deg = 10.0;
  o.seen_through_share = 1.5;
  EXPECT_NE(o.Validate().message().find("seen_through_share"), std::string::npos);
  o.seen_through_share = 0.4;
  o.side_ends_share = -0.1;
  EXPECT_NE(o.Validate().message().find("side_ends_share"), std::string::npos);
  o.side_ends_share = 0.55;
  o.side_ends_alone_share = 1.5;
  EXPECT_NE(o.Validate().message().find("side_ends_alone_share"), std::string::npos);
  o.side_ends_alone_share = 0.55;
  o.seam_depth_per_rms = -1.0;
  EXPECT_NE(o.Validate().message().find("seam_depth_per_rms"), std::string::npos);
}

// A carton of the layer under another that stands on it right at the
// visible part's edge: that side is not free (the face may go on under the
// box on it). Seen from beside the upper box, the pixels just past the side
// show the upper box's top a box height above the face: the side is
// occluded. Seen from above the upper box, perspective hides the face's own
// band along that side as well: the side is unknown. Here the lower box is
// longer than the reading, so a free side there would be a wrong box.
TEST(RefineOnGraspFaceTest, ASideUnderABoxStandingOnTheFaceIsNotFree) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const BoxDims lower{0.55, 0.30, 0.25};
  // The upper carton covers the lower one's +x end from x = 0.125.
  const SceneBox under = Flat(lower, 0.0, 0.0);
  const SceneBox over = Flat(carton_l, 0.125 + carton_l.l / 2.0, 0.0, lower.h);
  for (const auto& [camera_x, expected] :
       {std::pair{0.15, SideKind::kOccluded}, std::pair{0.35, SideKind::kUnknown}}) {
    Scene scene;
    scene.camera = CameraIntrinsics{};
    scene.world_T_camera =
        LookAtCamera(Eigen::Vector3d(camera_x, 0.0, lower.h), 1.2, 5.0, 0.0, 0.0);
    scene.boxes = {under, over};
    const FlatScene rendered = RenderExact(scene);
    const DepthImage& depth = rendered.depth;
    const GroundTruthBox& gt = rendered.rendered.boxes[0];
    // The reading: a carton_l on the visible 0.4 m of the lower top,
    // x in [-0.275, 0.125]; its +a side (box x) is the one under the upper box.
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, -0.075, 0.0, 0.0);
    const RefinementResult r =
        RefineOnGraspFace(depth, carton_l, TopFace(gt), RefinementOptions{}, &pose);
    EXPECT_EQ(r.sides[0], expected) << "camera at x = " << camera_x;
    EXPECT_EQ(r.sides[1], SideKind::kFree) << "camera at x = " << camera_x;
  }
}

// A reading turned 16 degrees on an isolated carton: its first step turns
// it back by ~15, more than the 12 a refinement may turn a hypothesis
// (max_turn_deg). With first_step_give_up_factor 1 it ends there, moved too
// far; off, it goes on and is read back onto the carton. The default, 2,
// ends only readings that far twice over, none of which came back within
// the limits on the evaluation sets.
TEST(RefineOnGraspFaceTest, AReadingFarAfterItsFirstStepEndsThere) {
  const FlatScene s = RenderFlat({Flat(kCartonS, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  for (const double factor : {1.0, 0.0}) {
    RefinementOptions o;
    o.first_step_give_up_factor = factor;
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.0, 0.0, 16.0);
    const RefinementResult r = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), o, &pose);
    const double turn_deg = ComparePoses(pose, gt.camera_T_box, kCartonS).rotation_deg;
    if (factor > 0.0) {
      EXPECT_FALSE(r.ok);
      EXPECT_EQ(r.steps, 1);
    } else {
      EXPECT_TRUE(r.ok);
      EXPECT_LT(turn_deg, 2.0);
    }
  }
  RefinementOptions bad;
  bad.first_step_give_up_factor = 0.5;
  EXPECT_NE(std::string(bad.Validate().message()).find("first_step_give_up_factor"),
            std::string::npos);
}

// A carton a centimetre long (a bulge, or an active stereo camera's
// fattened edges), read flush with its -x end: the +x side runs on by
// 12 mm and then ends. It is free where the face ends (the face's only side
// in doubt, its opposite free), and the box is centred on the measured face.
TEST(RefineOnGraspFaceTest, AFaceARimTooLongEndsWhereItsPointsEnd) {
  const BoxDims bulging{kCartonS.l + 0.012, kCartonS.b, kCartonS.h};
  const FlatScene s = RenderFlat({Flat(bulging, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  const Eigen::Isometry3d flush = Moved(gt.camera_T_box, -0.006, 0.0, 0.0);
  Eigen::Isometry3d pose = flush;
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  ASSERT_TRUE(r.ok);
  for (SideKind k : r.sides) EXPECT_EQ(k, SideKind::kFree);
  EXPECT_NEAR(r.extent_a_m, bulging.l, 0.008);
  EXPECT_LT(ComparePoses(pose, gt.camera_T_box, bulging).translation_m, 0.004);
  // The rule off: the side runs on, as a bigger face's would.
  RefinementOptions off;
  off.rim_ends_side = false;
  pose = flush;
  const RefinementResult r_off = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), off, &pose);
  EXPECT_EQ(r_off.sides[0], SideKind::kContinues);
}

// The same rim with a taller box standing against the opposite side, which
// hides it (occluded: the face may go on under it). With the other two
// sides free the rim still ends the face, and the box is placed from it
// (RefinementOptions::rim_beside_occluded): an active stereo camera's
// fattened top in a heap, its other long side behind a box in front.
TEST(RefineOnGraspFaceTest, ARimEndsTheFaceWhenItsOppositeSideIsOccluded) {
  const BoxDims bulging{kCartonS.l, kCartonS.b + 0.012, kCartonS.h};
  const BoxDims tall{0.30, 0.20, 0.35};
  const SceneBox carton = Flat(bulging, 0.0, 0.0);
  const SceneBox in_front = Flat(tall, 0.0, -(bulging.b / 2.0 + tall.b / 2.0 + 0.004));
  Scene scene;
  scene.camera = CameraIntrinsics{};
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d(0.0, 0.02, bulging.h), 1.3, -12.0, 8.0, 0.0);
  scene.boxes = {carton, in_front};
  const FlatScene rendered = RenderExact(scene);
  const DepthImage& depth = rendered.depth;
  const GroundTruthBox& gt = rendered.rendered.boxes[0];
  // The reading flush with the occluded -y side: +y runs on by 12 mm.
  const Eigen::Isometry3d flush = Moved(gt.camera_T_box, 0.0, -0.006, 0.0);
  Eigen::Isometry3d pose = flush;
  const RefinementResult r =
      RefineOnGraspFace(depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.sides[0], SideKind::kFree);
  EXPECT_EQ(r.sides[1], SideKind::kFree);
  EXPECT_EQ(r.sides[2], SideKind::kFree);
  EXPECT_EQ(r.sides[3], SideKind::kOccluded);
  // Placed from the rim: its +y side where the face ends, 6 mm from the
  // bulging carton's centre.
  const PoseError e = ComparePoses(pose, gt.camera_T_box, bulging);
  EXPECT_NEAR(e.translation_m, 0.006, 0.003);
  EXPECT_LT(e.rotation_deg, 1.0);
  // The rule off: the side runs on, and nothing measures the face across.
  RefinementOptions off;
  off.rim_beside_occluded = false;
  pose = flush;
  const RefinementResult r_off = RefineOnGraspFace(depth, kCartonS, TopFace(gt), off, &pose);
  EXPECT_EQ(r_off.sides[2], SideKind::kContinues);
  EXPECT_EQ(r_off.sides[3], SideKind::kOccluded);
}

// The same carton with a groove in its rim (a line of missing returns 3-6
// mm past the reading's side, as an active stereo camera's noise leaves in
// a fattened edge) and a colour image that shows the carton but no line
// there: the groove is no seam (colour_confirms_seam), and the side is
// what it would be without it, a rim that ends 12 mm out: free.
TEST(RefineOnGraspFaceTest, AGrooveTheColourDropsInARimLeavesTheRim) {
  const BoxDims bulging{kCartonS.l + 0.012, kCartonS.b, kCartonS.h};
  FlatScene s = RenderFlat({Flat(bulging, 0.0, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  const Eigen::Isometry3d flush = Moved(gt.camera_T_box, -0.006, 0.0, 0.0);
  const Eigen::Isometry3d box_T_camera = flush.inverse();
  const int w = s.depth.camera.width, h = s.depth.camera.height;
  s.depth.grey.assign(static_cast<size_t>(w) * h, 90.0f);
  int grooved = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      float& z = s.depth.z[static_cast<size_t>(v) * w + u];
      if (std::isnan(z)) continue;
      const Eigen::Vector3d p = box_T_camera * (z * PixelRay(s.depth.camera, u, v));
      if (p.z() < kCartonS.h / 2 - 0.01) continue;  // the top face only
      s.depth.grey[static_cast<size_t>(v) * w + u] = 150.0f;
      if (p.x() > kCartonS.l / 2 + 0.003 && p.x() < kCartonS.l / 2 + 0.006) {
        z = std::numeric_limits<float>::quiet_NaN();
        ++grooved;
      }
    }
  }
  ASSERT_GT(grooved, 50);
  Eigen::Isometry3d pose = flush;
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  ASSERT_TRUE(r.ok);
  for (SideKind k : r.sides) EXPECT_EQ(k, SideKind::kFree);
  EXPECT_LT(ComparePoses(pose, gt.camera_T_box, bulging).translation_m, 0.004);
  // Without the colour rule the groove is a seam, where the face is read.
  RefinementOptions depth_only;
  depth_only.colour_confirms_seam = 0.0;
  pose = flush;
  EXPECT_EQ(RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), depth_only, &pose).sides[0],
            SideKind::kSeam);
}

// The rim rule does not make a box of another size this one: a face whose
// other axis is 3 cm short of the box, or that runs on 4 cm (past the band a
// side is read in), keeps a side that runs on.
TEST(RefineOnGraspFaceTest, ARimDoesNotMakeAnotherSizeTheBox) {
  for (const BoxDims& other : {BoxDims{kCartonS.l + 0.012, kCartonS.b - 0.03, kCartonS.h},
                               BoxDims{kCartonS.l + 0.04, kCartonS.b, kCartonS.h}}) {
    const FlatScene s = RenderFlat({Flat(other, 0.0, 0.0)});
    const GroundTruthBox& gt = s.rendered.boxes[0];
    Eigen::Isometry3d pose = Moved(gt.camera_T_box, -(other.l - kCartonS.l) / 2.0, 0.0, 0.0);
    const RefinementResult r =
        RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
    EXPECT_NE(r.sides[0], SideKind::kFree) << other.l << " x " << other.b;
  }
}

// Two cartons end to end, 3 mm apart, the first 6 mm long (a bulge): read
// from its free end, its seam side falls 6-9 mm short of the gap, past the
// 6 mm either way a seam is looked for. The outward extension of the search
// (seam_search_outward_m) finds it; without it the side runs on.
TEST(RefineOnGraspFaceTest, ASeamPastAFaceThatReadsLongIsFoundOutward) {
  const BoxDims bulging{kCartonS.l + 0.006, kCartonS.b, kCartonS.h};
  const FlatScene s = RenderFlat(
      {Flat(bulging, 0.0, 0.0), Flat(kCartonS, (bulging.l + kCartonS.l) / 2.0 + 0.003, 0.0)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  const Eigen::Isometry3d from_free_end = Moved(gt.camera_T_box, -0.003, 0.0, 0.0);
  RefinementOptions no_rim;  // the seam alone, not the rim rule, is tested
  no_rim.rim_ends_side = false;
  Eigen::Isometry3d pose = from_free_end;
  const RefinementResult r = RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), no_rim, &pose);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.sides[0], SideKind::kSeam);
  EXPECT_EQ(r.sides[1], SideKind::kFree);
  EXPECT_NEAR(r.extent_a_m, bulging.l, 0.006);
  RefinementOptions symmetric = no_rim;
  symmetric.seam_search_outward_m = 0.0;
  pose = from_free_end;
  EXPECT_EQ(RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), symmetric, &pose).sides[0],
            SideKind::kContinues);
}

// A carton with another one beside its +x end, set off across it so that
// the two meet along only 6 cm of the carton's 20 cm end (their tops
// level, no gap): the face ends at that side along most of it, and the side
// is free there (RefinementOptions::side_ends_share); with the rule off it
// is not. A carton the other one meets along all of its end (3 mm apart)
// still has a seam there, not a free side.
TEST(RefineOnGraspFaceTest, ASideANeighbourMeetsAtOneCornerIsFree) {
  const FlatScene s =
      RenderFlat({Flat(kCartonS, 0.0, 0.0), Flat(kCartonS, kCartonS.l, kCartonS.b - 0.06)});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  const Eigen::Isometry3d start = Moved(gt.camera_T_box, 0.004, -0.003, 1.0);
  Eigen::Isometry3d pose = start;
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  ASSERT_TRUE(r.ok);
  for (SideKind k : r.sides) EXPECT_EQ(k, SideKind::kFree);
  const PoseError e = ComparePoses(pose, gt.camera_T_box, kCartonS);
  EXPECT_LT(e.translation_m, 0.003);
  EXPECT_LT(e.rotation_deg, 1.0);
  RefinementOptions off;
  off.side_ends_share = 0.0;
  pose = start;
  EXPECT_NE(RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), off, &pose).sides[0],
            SideKind::kFree);

  const FlatScene whole =
      RenderFlat({Flat(kCartonS, 0.0, 0.0), Flat(kCartonS, kCartonS.l + 0.003, 0.0)});
  pose = Moved(whole.rendered.boxes[0].camera_T_box, 0.004, -0.003, 1.0);
  EXPECT_EQ(RefineOnGraspFace(whole.depth, kCartonS, TopFace(whole.rendered.boxes[0]),
                              RefinementOptions{}, &pose)
                .sides[0],
            SideKind::kSeam);
}

// A carton whose level neighbour meets its +x end along 10 of its 20 cm:
// the face ends at that side along half of the side's stretch. By default
// (side_ends_share 0.35) the side is free, as are its three others; with
// the share of session 28 (0.55) it is not. With taller cartons standing
// against its -x end and its -y side (two sides hidden) it runs on
// (RefinementOptions::side_ends_alone_share: a reading across two bricks
// lying in an L with level tops ends along part of a side too), with one
// of them it is free, and so it is with both when the share it ends along
// passes side_ends_alone_share.
TEST(RefineOnGraspFaceTest, ASideEndingAlongHalfIsFreeWithTwoOtherSidesMeasured) {
  const SceneBox neighbour = Flat(kCartonS, kCartonS.l, 0.10);
  const FlatScene s = RenderFlat({Flat(kCartonS, 0.0, 0.0), neighbour});
  const GroundTruthBox& gt = s.rendered.boxes[0];
  Eigen::Isometry3d pose = Moved(gt.camera_T_box, 0.004, -0.003, 1.0);
  const RefinementResult r =
      RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), RefinementOptions{}, &pose);
  ASSERT_TRUE(r.ok);
  for (SideKind k : r.sides) EXPECT_EQ(k, SideKind::kFree);
  EXPECT_LT(ComparePoses(pose, gt.camera_T_box, kCartonS).translation_m, 0.003);
  RefinementOptions session28;
  session28.side_ends_share = 0.55;
  pose = Moved(gt.camera_T_box, 0.004, -0.003, 1.0);
  EXPECT_NE(RefineOnGraspFace(s.depth, kCartonS, TopFace(gt), session28, &pose).sides[0],
            SideKind::kFree);

  const BoxDims taller{0.30, 0.20, 0.30};
  const SceneBox past_end = Flat(taller, -kCartonS.l - 0.003, 0.0);
  const SceneBox past_side = Flat(taller, 0.0, -kCartonS.b - 0.003);
  auto plus_a = [&](const std::vector<SceneBox>& boxes, const RefinementOptions& o) {
    const FlatScene scene = RenderFlat(boxes);
    const GroundTruthBox& box = scene.rendered.boxes[0];
    Eigen::Isometry3d p = Moved(box.camera_T_box, 0.004, -0.003, 1.0);
    return RefineOnGraspFace(scene.depth, kCartonS, TopFace(box), o, &p);
  };
  const RefinementResult two_hidden =
      plus_a({Flat(kCartonS, 0.0, 0.0), neighbour, past_end, past_side}, RefinementOptions{});
  EXPECT_EQ(two_hidden.sides[1], SideKind::kOccluded);
  EXPECT_EQ(two_hidden.sides[3], SideKind::kOccluded);
  EXPECT_EQ(two_hidden.sides[0], SideKind::kContinues);
  EXPECT_EQ(plus_a({Flat(kCartonS, 0.0, 0.0), neighbour, past_end}, RefinementOptions{}).sides[0],
            SideKind::kFree)
      << "one other side hidden";
  RefinementOptions alone;
  alone.side_ends_alone_share = 0.4;
  EXPECT_EQ(plus_a({Flat(kCartonS, 0.0, 0.0), neighbour, past_end, past_side}, alone).sides[0],
            SideKind::kFree);
}

}  // namespace
}  // namespace cornerpose::testing
