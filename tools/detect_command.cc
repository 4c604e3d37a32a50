#include "tools/detect_command.h"

#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/box/box_models.h"
#include "common/io/cloud_io.h"
#include "common/perception/camera_model.h"
#include "common/perception/detector.h"
#include "common/viz/detection_json.h"
#include "common/viz/detection_ply.h"
#include "common/viz/detection_png.h"
#include "tools/command_args.h"

namespace cornerpose::tools {
namespace {

constexpr char kHelp[] =
    "usage: cornerpose detect --cloud FILE --box L,B,H|NAME [outputs] [options]\n"
    "\n"
    "input:\n"
    "  --cloud FILE         .pcd (ascii/binary/binary_compressed), .ply, or a 16-bit\n"
    "                       depth .png in millimetres (needs --intrinsics)\n"
    "  --box L,B,H|NAME     box size in metres, or brick, carton_s, carton_l,\n"
    "                       carton_sq, carton_flat\n"
    "  --intrinsics K       fx,fy,cx,cy or width,height,fx,fy,cx,cy: the camera of a\n"
    "                       depth image, or of an unorganized cloud (default Kinect VGA)\n"
    "  --color FILE         colour PNG registered to the organized cloud or depth image\n"
    "                       (seam cues; the --png is drawn over it). Default: the PCD's\n"
    "                       rgb/rgba field, or NAME.color.png beside a depth NAME.png\n"
    "outputs (any number):\n"
    "  --json OUT           boxes, edges, corners and per-stage timings\n"
    "  --ply OUT            coloured cloud: grey points, red edge points, segments,\n"
    "                       green box wireframes, yellow corners\n"
    "  --png OUT            depth image with the same drawn over it\n"
    "  --edges OUT          edge points as a PCD (for tools/score.py edges)\n"
    "detector (defaults are the paper's values):\n"
    "  --radius M           edge neighbourhood radius r_s (0.02)\n"
    "  --threshold T        edge score threshold t_h (0.35)\n"
    "  --samples N          neighbours sampled per point, 0 = all (64)\n"
    "  --ransac_threshold M RANSAC line inlier distance (0.01)\n"
    "  --meet_distance M    corner: largest distance between two edges' lines (0.01)\n"
    "  --meet_along_view F  ... along the line of sight F times that (depth noise; 3;\n"
    "                       1: the paper's sphere)\n"
    "  --coarse_step N      organized frames: score 1 pixel in N x N first, then only\n"
    "                       pixels near a hit; 1 = every pixel (3)\n"
    "  --lattice_radius PX  organized frames: the edge stage scores every k-th pixel,\n"
    "                       k = r_s in pixels / PX at the median depth (0 = every pixel)\n"
    "  --denoise BOOL       score from the neighbours' median depth (true); false is\n"
    "                       the paper's formula exactly, for clouds not taken by a camera\n"
    "                       at the origin\n"
    "  --threads N          worker threads (2)\n"
    "  --faces BOOL         face-first proposals from planar patches (true); false is\n"
    "                       the corner-only detector\n"
    "  --layer_check BOOL   a box that a seam bounds on a layer that tiles must be one\n"
    "                       of its tiles (true)\n"
    "  --floor_check BOOL   no box reaches through the floor, the farthest large plane\n"
    "                       (true)\n"
    "  --kept_seams BOOL    a side running on flat is a seam where it lies against a\n"
    "                       box already found, coplanar and aligned (true)\n"
    "  --empty_window N     a frame where nothing is found has its faces found and\n"
    "                       judged once more with the planar patches' normal window N\n"
    "                       cells wide each way of its centre (4; 0: never)\n"
    "  --pairs BOOL         two boxes declined only for one side running on flat, those\n"
    "                       sides against each other, end each other when both pass\n"
    "                       so and their outline tiles one way with two faces (true)\n"
    "  --seen_through S     a reading with no point just inside one side, where that\n"
    "                       share of the pixels there not hidden see behind its plane,\n"
    "                       is declined: the face ends before that side (0.4; 0: off)\n"
    "  --level_check M      a box whose top is level with two boxes beside it (a\n"
    "                       layer) but whose bottom would lie more than M below\n"
    "                       theirs is taken out (0.05; 0: off)\n"
    "  --flush_layer BOOL   ... or with one it lies flush against, touching and\n"
    "                       aligned (true)\n"
    "  --turned_check BOOL  a box with a side not measured is taken out when its face\n"
    "                       turned a quarter at a measured corner is a box too (true)\n"
    "  --corner_tilt BOOL   a corner's reading declined unrefined or moved too far is\n"
    "                       judged again with its face on the depth's plane (true)\n"
    "  --turned_hidden BOOL a face hidden on two sides across each other is left to\n"
    "                       the turned check, not declined (true; off with the check)\n"
    "  --shifted_check BOOL a box seamed on both sides of an axis is taken out when\n"
    "                       its face shifted half its width is a box with more free\n"
    "                       sides (tape edges taken for seams; true)\n"
    "  --paired_check BOOL  two boxes side by side whose faces together are another\n"
    "                       face of the box are taken out when that one box is judged\n"
    "                       a box too (flap seams taken for seams; true)\n"
    "  --retake_outranked BOOL a box a check took out no longer blocks the readings\n"
    "                       it outranked: they are judged again (true)\n"
    "  --turned_proposals BOOL  a hypothesis declined for a side on flat proposes its\n"
    "                       face turned a quarter at its measured corners (false)\n"
    "  --unseen_sides BOOL  a side with nothing seen near it (a shadow) may hide a\n"
    "                       longer side of the box, as an occluded one does (true)\n"
    "  --unseen_longer S    ... unless S of the box so read longer is seen through\n"
    "                       (0.2; 0: never)\n"
    "  --layer_plane DEG    boxes side by side on one plane (a layer) take the plane\n"
    "                       fitted through all their faces when within DEG of it (12;\n"
    "                       0: every box keeps its own face's plane)\n"
    "  --layer_adopt DEG    ... and a face tilted up to DEG takes it when its pixels fit\n"
    "                       the plane about as well as their own (25)\n"
    "  --layer_turn N       a box whose face touches N others on its plane that agree\n"
    "                       on their in-plane turn takes the layer's turn (3; 0: every\n"
    "                       box keeps its own)\n"
    "  --floor_rest DEG     a box on the floor whose bottom is tilted into it by up to\n"
    "                       DEG lies flat on it (15; 0: off)\n"
    "  --corner_readings N  a corner proposes the N readings of its two edges that\n"
    "                       fit them best (3; 0: every reading, up to six)\n"
    "  --seam_colour SHARE  with a colour image, a groove in the depth is a seam only\n"
    "                       where an image line runs along SHARE of the side (0.5;\n"
    "                       0: the depth alone)\n"
    "  --sparse_seam SHARE  a line where SHARE more of the returns are missing than\n"
    "                       beside it is a seam (a gap finer than a pixel; 0.05; 0: off)\n"
    "  --eroded_faces SHARE a planar patch smaller than a face but SHARE of it along\n"
    "                       both sides proposes the face centred on it (0.65; 0: off)\n"
    "  --eroded_beside BOOL ... also when the outline tiles one way (true)\n"
    "  --edge_pairs BOOL    two parallel edge segments a side of the box apart propose\n"
    "                       the face between them (true)\n"
    "  --border_band BOOL   a face cut by the image border: the view ends where a run of\n"
    "                       pixels with no return reaches the border (true)\n"
    "  --floor_faces BOOL   judge face proposals that lie on the floor found (false: they\n"
    "                       would reach into it)\n"
    "  --merge_patches N    planar patches within N cells of each other on one plane\n"
    "                       are one (a face noise broke up; 2; 0: no merging)\n"
    "  --merged_pieces BOOL ... and the pieces so merged propose their faces too (two\n"
    "                       boxes' faces on one plane, a shadow between them; true)\n"
    "  --tile_uncued BOOL   a face that runs on flat with no seam anywhere is a tile of\n"
    "                       its layer when the layer tiles (false: a laptop lid is not\n"
    "                       boxes; true for cells that see only layers of known boxes)\n"
    "  --size_tolerance M   how far a box may be off its nominal size and still be it\n"
    "                       (unset: each stage's own tolerance, 1-2.5 cm)\n"
    "  --short_both M       a face measured short of the box by more than M on both\n"
    "                       axes is a smaller box (0.012; --size_tolerance T: T; 0: off)\n"
    "  --side_allowance M   on a box's faces but the one it shows most, depth up to M\n"
    "                       behind the tolerance is no evidence either way (time-of-\n"
    "                       flight multipath in concave creases; 0.025; 0: off)\n"
    "  --seam_outward M    a seam is looked for 6 mm either side of a side and M\n"
    "                       further out (0.004; 0: symmetric)\n"
    "  --layer_down BOOL    a box found proposes the boxes beside it a layer down too\n"
    "                       (a pallet stacked at two heights; true)\n"
    "  --past_declined N    a neighbour declined only for a side that runs on flat\n"
    "                       still proposes its own, up to N declined in a row (2;\n"
    "                       0: the chain of neighbours stops at the first)\n"
    "  --seam_turn M        a seam along a side at least M long turns the face as a\n"
    "                       free side does (0.1; 0: seams give a position only)\n"
    "  --end_on_flat M      a hypothesis whose first refinement step finds a side\n"
    "                       running on flat and no seam, moving it less than M, ends\n"
    "                       there (declined; 0.003; 0: every step)\n"
    "  --slat_gap M         a face free on two opposite sides, its plane going on\n"
    "                       past a gap of 1.5 cm to M beyond each (a pallet's deck\n"
    "                       board, a slat), is declined (0.06; 0: off)\n"
    "  --give_up K          a reading whose first refinement step moved it more than K\n"
    "                       times the 5 cm / 12 degree limits ends there (2; 0: never)\n"
    "  --extra_step M       one refinement step more when the last still turned the\n"
    "                       face's corners by more than M (0.003; 0: never)\n"
    "  --rim_sides BOOL     a side where the face runs on but ends within 2 cm is free\n"
    "                       there, when it is the face's only side in doubt (true)\n"
    "  --rim_occluded BOOL  ... also when its opposite side is occluded (a box standing\n"
    "                       in front there) and its other two sides are measured (true)\n"
    "  --side_ends SHARE    a side where the face ends within 5 mm along SHARE of it\n"
    "                       is free, whatever lies flat past the rest (0.35; 0: off)\n"
    "  --side_ends_alone SHARE ... along less than SHARE of it only when two of the\n"
    "                       face's three other sides are measured (0.55)\n"
    "  --seam_depth_rms K   a groove along a side is a seam only when deeper than K\n"
    "                       times the face's own RMS about its plane (1; 0: 1.5 mm alone)\n"
    "  --anchored_faces BOOL a planar patch that does not tile (an L of box tops, a\n"
    "                       layer cut by the border) proposes a face in each of its\n"
    "                       corners (false)\n"
    "  --seam_split BOOL    ... and faces framed by the seams seen inside it (lines of\n"
    "                       missing returns or grooves) and its sides in view (true)\n"
    "  --border_faces BOOL  a planar patch at the image border no bigger than a face\n"
    "                       proposes that face (true)\n"
    "  --leaving_view N     a face the image border cuts is returned when free sides or\n"
    "                       seams end it all round, with a free side on N of its two\n"
    "                       axes (1; 2: on both; 0: seams suffice)\n"
    "  --out_of_view BOOL   a face the border cuts on one side is returned when its\n"
    "                       other sides end it and it is seen to the border longer\n"
    "                       than any shorter side of the box, over 60% of its length\n"
    "                       (true)\n"
    "  --corner_out SHARE   a face at most SHARE of which lies past the border, every\n"
    "                       side of it read, is judged as in view (0.1; 0: every\n"
    "                       corner in view)\n"
    "  --score_in_view BOOL a box's score is its support times the share of its\n"
    "                       outline in the image: boxes partly out of view rank\n"
    "                       below those wholly in view (true)\n"
    "  --retry_declined BOOL a pose refined and declined is judged once more when\n"
    "                       proposed again from another start (true)\n"
    "  --patch_window N     planar patches: a cell's normal from (2N+1)^2 cells of 4 px\n"
    "                       (2)\n"
    "  --max_declined N     report the N strongest declined candidates with their\n"
    "                       reasons (8; 0-1000)\n"
    "  --kdtree             unorganized clouds: score edges over a k-d tree (the\n"
    "                       paper's way) instead of projecting onto the camera grid\n"
    "  --quiet              print nothing but errors\n";

absl::Status Run(const CommandArgs& args) {
  auto get = [&](const std::string& k) { return args.Get(k); };
  if (!get("cloud")) return absl::InvalidArgumentError("--cloud is required");
  if (!get("box")) return absl::InvalidArgumentError("--box is required");
  absl::StatusOr<BoxDims> box = ParseBoxDims(*get("box"));
  if (!box.ok()) return box.status();

  DetectorOptions options;
  options.box = *box;
  LoadOptions load;
  if (auto k = get("intrinsics")) {
    absl::StatusOr<CameraIntrinsics> intrinsics = ParseIntrinsics(*k);
    if (!intrinsics.ok()) return intrinsics.status();
    load.intrinsics = *intrinsics;
    options.camera = *intrinsics;
  }
  for (absl::Status s :
       {args.SetDouble("radius", &options.edge_points.radius_m),
        args.SetDouble("threshold", &options.edge_points.threshold),
        args.SetInt("samples", &options.edge_points.max_samples),
        args.SetDouble("ransac_threshold", &options.segments.ransac_threshold_m),
        args.SetDouble("meet_distance", &options.clubbing.meet_distance_m),
        args.SetDouble("meet_along_view", &options.clubbing.meet_along_view_factor),
        args.SetInt("threads", &options.num_threads),
        args.SetInt("coarse_step", &options.edge_points.coarse_step),
        args.SetDouble("lattice_radius", &options.edge_lattice_radius_px),
        args.SetBool("denoise", &options.edge_points.denoise),
        args.SetBool("faces", &options.face_proposals),
        args.SetBool("layer_check", &options.faces.check_layer_tiling),
        args.SetBool("floor_check", &options.floor_check),
        args.SetDouble("level_check", &options.max_below_neighbours_m),
        args.SetBool("flush_layer", &options.flush_neighbour_is_layer),
        args.SetBool("turned_check", &options.turned_check),
        args.SetBool("turned_hidden", &options.acceptance.turned_hidden_corner_to_check),
        args.SetBool("corner_tilt", &options.corner_tilt_onto_depth),
        args.SetBool("shifted_check", &options.shifted_check),
        args.SetBool("paired_check", &options.paired_check),
        args.SetBool("retake_outranked", &options.retake_outranked),
        args.SetBool("unseen_sides", &options.acceptance.check_unseen_sides),
        args.SetDouble("unseen_longer", &options.acceptance.unseen_longer_see_through),
        args.SetBool("turned_proposals", &options.turned_proposals),
        args.SetDouble("layer_plane", &options.layer_plane.max_angle_deg),
        args.SetDouble("layer_adopt", &options.layer_plane.adopt_angle_deg),
        args.SetInt("layer_turn", &options.layer_turn.min_agreeing),
        args.SetDouble("floor_rest", &options.floor_rest.max_tilt_deg),
        args.SetInt("corner_readings", &options.pose.max_readings_per_corner),
        args.SetDouble("seam_colour", &options.refinement.colour_confirms_seam),
        args.SetDouble("sparse_seam", &options.refinement.sparse_seam_missing),
        args.SetDouble("eroded_faces", &options.faces.min_eroded_share),
        args.SetBool("eroded_beside", &options.faces.eroded_beside_tile),
        args.SetBool("edge_pairs", &options.edge_pairs.enabled),
        args.SetBool("border_band", &options.acceptance.border_band_ends_view),
        args.SetBool("floor_faces", &options.judge_faces_on_floor),
        args.SetInt("merge_patches", &options.faces.patches.merge_gap_cells),
        args.SetBool("tile_uncued", &options.refinement.tile_uncued_sides),
        args.SetInt("max_declined", &options.max_declined),
        args.SetBool("border_faces", &options.faces.propose_at_border),
        args.SetInt("leaving_view", &options.acceptance.leaving_view_free_axes),
        args.SetBool("out_of_view", &options.acceptance.face_may_run_out_of_view),
        args.SetDouble("corner_out", &options.acceptance.max_out_of_view_share),
        args.SetBool("score_in_view", &options.score_in_view),
        args.SetBool("kept_seams", &options.acceptance.kept_box_ends_side),
        args.SetBool("pairs", &options.acceptance.pairs_end_each_other),
        args.SetDouble("seen_through", &options.refinement.seen_through_share),
        args.SetInt("empty_window", &options.empty_frame_window_cells),
        args.SetBool("anchored_faces", &options.faces.anchored.enabled),
        args.SetBool("seam_split", &options.faces.seam_split.enabled),
        args.SetBool("merged_pieces", &options.faces.propose_merged_pieces),
        args.SetBool("rim_sides", &options.refinement.rim_ends_side),
        args.SetBool("rim_occluded", &options.refinement.rim_beside_occluded),
        args.SetDouble("side_ends", &options.refinement.side_ends_share),
        args.SetDouble("side_ends_alone", &options.refinement.side_ends_alone_share),
        args.SetDouble("seam_depth_rms", &options.refinement.seam_depth_per_rms),
        args.SetDouble("end_on_flat", &options.refinement.end_on_flat_shift_m),
        args.SetDouble("give_up", &options.refinement.first_step_give_up_factor),
        args.SetDouble("slat_gap", &options.refinement.slat_gap_max_m),
        args.SetDouble("extra_step", &options.refinement.extra_step_corner_move_m),
        args.SetDouble("seam_turn", &options.refinement.seam_turn_min_length_m),
        args.SetBool("layer_down", &options.neighbours_a_layer_down),
        args.SetInt("past_declined", &options.neighbour_steps_past_declined),
        args.SetDouble("seam_outward", &options.refinement.seam_search_outward_m),
        args.SetBool("retry_declined", &options.retry_declined),
        args.SetInt("patch_window", &options.faces.patches.window_cells),
        args.SetDouble("side_allowance", &options.evidence.side_face_allowance_m),
        args.SetDouble("short_both", &options.acceptance.max_short_both_axes_m)}) {
    if (!s.ok()) return s;
  }
  if (get("size_tolerance")) {
    double t = 0.0;
    if (absl::Status s = args.SetDouble("size_tolerance", &t); !s.ok()) return s;
    options.size_tolerance_m = t;
  }
  if (auto c = get("color")) load.color_path = *c;
  options.project_unorganized = !args.Has("kdtree");
  // r_s is also the gap at which a segment ends (Algorithm 1).
  SetEdgeRadius(options.edge_points.radius_m, &options);

  absl::StatusOr<PointCloud> cloud = LoadPointCloud(*get("cloud"), load);
  if (!cloud.ok()) return cloud.status();
  absl::StatusOr<Detection> det = DetectBoxes(*cloud, options);
  if (!det.ok()) return det.status();

  if (!args.Has("quiet")) {
    PrintDetection(*get("cloud"), cloud->size(), *det);
    for (const DeclinedCandidate& d : det->declined) {
      const Eigen::Vector3d t = d.camera_T_box.translation();
      std::printf("  declined: support %.2f  centre (%.3f, %.3f, %.3f) m  %s\n", d.score, t.x(),
                  t.y(), t.z(), d.reason.c_str());
    }
  }
  if (auto p = get("json")) {
    if (absl::Status s = WriteDetectionJson(*p, *det, *box); !s.ok()) return s;
  }
  if (auto p = get("ply")) {
    if (absl::Status s = WriteDetectionPly(*p, *cloud, *det, *box); !s.ok()) return s;
  }
  if (auto p = get("png")) {
    CameraIntrinsics camera = options.camera.value_or(CameraIntrinsics{});
    if (cloud->organized()) {
      if (absl::StatusOr<CameraIntrinsics> k = EstimateIntrinsics(*cloud); k.ok()) camera = *k;
    }
    if (absl::Status s = WriteDetectionPng(*p, *cloud, camera, *det, *box); !s.ok()) return s;
  }
  if (auto p = get("edges")) {
    if (absl::Status s = SavePoints(*p, det->edge_points); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

void PrintDetection(const std::string& label, std::optional<size_t> num_points,
                    const Detection& detection) {
  const Detection* det = &detection;
  const std::string points = num_points ? absl::StrCat(*num_points, " points, ") : "";
  std::printf("%s: %s%zu edge points, %zu segments, %zu corners, %zu boxes (%.1f ms)\n",
              label.c_str(), points.c_str(), det->edge_points.size(), det->segments.size(),
              det->corners.size(), det->boxes.size(), det->timings.total_ms);
  for (size_t i = 0; i < det->boxes.size(); ++i) {
    const DetectedBox& b = det->boxes[i];
    const Eigen::Vector3d t = b.camera_T_box.translation();
    const Eigen::Vector3d ypr = b.camera_T_box.linear().eulerAngles(2, 1, 0) * 180.0 / M_PI;
    std::printf(
        "  box %zu: score %.2f  centre (%.3f, %.3f, %.3f) m  zyx euler (%.1f, %.1f, %.1f) deg"
        "  grasp %s at (%.3f, %.3f, %.3f)\n",
        i, b.score, t.x(), t.y(), t.z(), ypr.x(), ypr.y(), ypr.z(), BoxFaceName(b.grasp_face),
        b.grasp_centre_camera.x(), b.grasp_centre_camera.y(), b.grasp_centre_camera.z());
  }
}

int RunDetect(const std::vector<std::string>& argv) {
  if (PrintHelpIfAsked(argv, kHelp)) return 0;
  absl::StatusOr<CommandArgs> args = ParseCommandArgs(argv,
                                                      {"cloud",
                                                       "box",
                                                       "intrinsics",
                                                       "json",
                                                       "ply",
                                                       "png",
                                                       "edges",
                                                       "radius",
                                                       "threshold",
                                                       "samples",
                                                       "ransac_threshold",
                                                       "meet_distance",
                                                       "meet_along_view",
                                                       "threads",
                                                       "coarse_step",
                                                       "lattice_radius",
                                                       "denoise",
                                                       "color",
                                                       "faces",
                                                       "layer_check",
                                                       "floor_check",
                                                       "level_check",
                                                       "flush_layer",
                                                       "turned_check",
                                                       "turned_hidden",
                                                       "corner_tilt",
                                                       "shifted_check",
                                                       "paired_check",
                                                       "retake_outranked",
                                                       "unseen_sides",
                                                       "unseen_longer",
                                                       "turned_proposals",
                                                       "layer_plane",
                                                       "layer_adopt",
                                                       "layer_turn",
                                                       "floor_rest",
                                                       "corner_readings",
                                                       "seam_colour",
                                                       "sparse_seam",
                                                       "eroded_faces",
                                                       "eroded_beside",
                                                       "merge_patches",
                                                       "tile_uncued",
                                                       "size_tolerance",
                                                       "max_declined",
                                                       "side_allowance",
                                                       "short_both",
                                                       "border_faces",
                                                       "leaving_view",
                                                       "out_of_view",
                                                       "corner_out",
                                                       "score_in_view",
                                                       "kept_seams",
                                                       "pairs",
                                                       "seen_through",
                                                       "empty_window",
                                                       "edge_pairs",
                                                       "border_band",
                                                       "floor_faces",
                                                       "anchored_faces",
                                                       "seam_split",
                                                       "merged_pieces",
                                                       "rim_sides",
                                                       "rim_occluded",
                                                       "side_ends",
                                                       "side_ends_alone",
                                                       "seam_depth_rms",
                                                       "end_on_flat",
                                                       "give_up",
                                                       "slat_gap",
                                                       "extra_step",
                                                       "seam_turn",
                                                       "layer_down",
                                                       "past_declined",
                                                       "seam_outward",
                                                       "retry_declined",
                                                       "patch_window"},
                                                      {"quiet", "kdtree"});
  if (!args.ok()) {
    std::fprintf(stderr, "cornerpose detect: %s\n\n%s",
                 std::string(args.status().message()).c_str(), kHelp);
    return 2;
  }
  if (absl::Status s = Run(*args); !s.ok()) {
    std::fprintf(stderr, "cornerpose detect: %s\n", s.ToString().c_str());
    return 1;
  }
  return 0;
}

}  // namespace cornerpose::tools
