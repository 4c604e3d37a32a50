#include "common/perception/detector.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/perception/camera_model.h"
#include "common/perception/internal/box_overlap.h"
#include "common/perception/internal/hypothesis_judge.h"
#include "common/perception/internal/kept_neighbours.h"
#include "common/perception/internal/paired_faces.h"
#include "common/perception/internal/parallel.h"
#include "common/perception/internal/view_share.h"
#include "common/perception/neighbour_hypotheses.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kMaxEdgeLattice = 4;
double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Points with a NaN, an infinity or a coordinate beyond any depth camera's
// range in any axis become NaN points (no return), so one bad value cannot
// poison the intrinsics fit or a neighbourhood; in a camera frame (organized)
// so do depths nearer than any depth camera measures (the pixel radius
// r fx / z grows without bound as z -> 0). Copies only when needed.
const PointCloud& SanitizeCloud(const PointCloud& cloud, PointCloud* storage) {
  constexpr float kMaxCoordinate = 100.0f;   // metres
  constexpr float kMinCameraDepthM = 0.01f;  // depth cameras' minimum range is centimetres
  const float min_depth = cloud.organized() ? kMinCameraDepthM : -kMaxCoordinate;
  auto bad = [min_depth](const Eigen::Vector3f& p) {
    return !(std::abs(p.x()) <= kMaxCoordinate && std::abs(p.y()) <= kMaxCoordinate &&
             p.z() >= min_depth && p.z() <= kMaxCoordinate) &&
           !(std::isnan(p.x()) && std::isnan(p.y()) && std::isnan(p.z()));
  };
  if (std::none_of(cloud.xyz.begin(), cloud.xyz.end(), bad)) return cloud;
  *storage = cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (Eigen::Vector3f& p : storage->xyz) {
    if (bad(p)) p = Eigen::Vector3f(nan, nan, nan);
  }
  return *storage;
}

void ApplySizeTolerance(double t, DetectorOptions* o) {
  o->faces.size_tolerance_m = t;
  o->refinement.tile_tolerance_m = 2.0 * t / 3.0;
  o->pose.length_tolerance_m = t + 0.01;
  o->acceptance.extent_tolerance_m = t + 0.01;
  o->acceptance.max_short_both_axes_m = t;
}

// What the refinement measured of a kept box's grasp face, for the checks
// after acceptance.
struct KeptReading {
  std::array<SideKind, 4> sides;
  std::array<std::optional<Eigen::Vector3d>, 4> past_gap;  // RefinementResult::past_gap
};

// Takes out the boxes (and their readings) for which `why(i)` gives a
// reason, declining each with it. True when one was taken out.
bool TakeOut(std::vector<DetectedBox>* boxes, std::vector<KeptReading>* readings,
             std::vector<DeclinedCandidate>* declined,
             const std::function<std::string(size_t)>& why) {
  size_t kept = 0;
  for (size_t i = 0; i < boxes->size(); ++i) {
    if (std::string reason = why(i); !reason.empty()) {
      declined->push_back({(*boxes)[i].camera_T_box, (*boxes)[i].score, std::move(reason)});
      continue;
    }
    (*boxes)[kept] = (*boxes)[i];
    (*readings)[kept] = (*readings)[i];
    ++kept;
  }
  const bool removed = kept < boxes->size();
  boxes->resize(kept);
  readings->resize(kept);
  return removed;
}

// The floor: the farthest large plane the camera sees (the planar patches
// on one plane, together at least floor_min_area_m2 and three of the box's
// largest faces, whose plane lies farthest from the camera along its
// normal: the floor or table under a pallet, a heap or a bin), with no more
// than floor_max_beyond_share of the frame beyond it (past
// floor_tolerance_m, or three times the floor's own scatter scaled by z^2
// to the point's depth). Found once a frame, before any hypothesis is
// judged (HypothesisJudge::SetFloor).
struct FloorPlane {
  Eigen::Vector3d normal, centroid;  // the normal points at the camera
  double rms = 0.0;                  // its points' scatter about it, metres
};
// The farthest plane through planar patches together at least min_area
// (FindFloor's first part). A patch's plane takes in every patch on it
// (within 10 degrees and floor_tolerance_m) and is fitted through all their
// points; `regather` times more, the plane so fitted takes in the patches
// on it again: a noisy floor's pieces tilt their own planes by several
// degrees, and measured from one piece the others a metre away lie
// centimetres off it.
std::optional<FloorPlane> FarthestPlane(const DepthImage& depth, const DetectorOptions& options,
                                        const PlanarPatches& found, int regather) {
  const BoxDims& d = options.box;
  const double largest_face = std::max({d.l * d.b, d.l * d.h, d.b * d.h});
  const double min_area = std::max(options.floor_min_area_m2, 3.0 * largest_face);
  auto area_of = [&](const PlanarPatch& patch) {
    return PatchCellsArea(patch, depth.camera.fx, found.step_px);
  };
  // Each patch's points summed once (count, sum, sum of outer products):
  // every seed and round gathers patches, not points.
  struct Moments {
    double area = 0.0, count = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  };
  const std::vector<PlanarPatch>& patches = found.patches;
  std::vector<Moments> moments(patches.size());
  for (size_t k = 0; k < patches.size(); ++k) {
    moments[k].area = area_of(patches[k]);
    for (const Eigen::Vector3d& q : patches[k].points) {
      moments[k].sum += q;
      moments[k].outer += q * q.transpose();
      moments[k].count += 1.0;
    }
  }
  std::optional<FloorPlane> floor;
  double floor_distance = 0.0;
  const double cos_floor = std::cos(10.0 * M_PI / 180.0);
  for (size_t seed = 0; seed < patches.size(); ++seed) {
    // A noisy floor comes out of the segmentation in pieces (an active
    // stereo camera at 2.5 m: none of them 0.36 m^2).
    if (moments[seed].area < 0.1 * min_area) continue;
    Eigen::Vector3d normal = patches[seed].normal, centroid = patches[seed].centroid;
    double area = 0.0, rms = 0.0;
    for (int round = 0; round <= regather; ++round) {
      double count = 0.0;
      area = 0.0;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
      for (size_t k = 0; k < patches.size(); ++k) {
        if (!(round == 0 && k == seed) &&
            (patches[k].normal.dot(normal) < cos_floor ||
             std::abs(normal.dot(patches[k].centroid - centroid)) > options.floor_tolerance_m)) {
          continue;
        }
        area += moments[k].area;
        sum += moments[k].sum;
        outer += moments[k].outer;
        count += moments[k].count;
      }
      if (count < 3.0) break;
      centroid = sum / count;
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(outer / count -
                                                         centroid * centroid.transpose());
      normal = eig.eigenvectors().col(0);
      if (normal.dot(centroid) > 0.0) normal = -normal;
      rms = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
    }
    if (area < min_area) continue;
    // The normal points at the camera, so the plane is n.x = -distance.
    const double distance = -normal.dot(centroid);
    if (distance > floor_distance) {
      floor_distance = distance;
      floor = FloorPlane{normal, centroid, rms};
    }
  }
  return floor;
}

// The floor: FarthestPlane, when nothing lies beyond it: a lower layer's
// top or a pallet deck may be the farthest plane found while the floor
// itself (noisy, or cut up) is no patch. Beyond: past the tolerance, or
// past three times the floor's own scatter at the point's depth. When the
// plane found so has too much beyond it (or none is found), the pieces are
// gathered again
// (FarthestPlane's regather, twice): a noisy stereo floor at 2-2.5 m
// behind a brick pallet came out in pieces of 0.04-0.06 m^2 whose planes
// gathered no floor, and the pallet's top was taken for it.
std::optional<FloorPlane> FindFloor(const DepthImage& depth, const DetectorOptions& options,
                                    const PlanarPatches& patches) {
  for (const int regather : {0, 2}) {
    std::optional<FloorPlane> floor = FarthestPlane(depth, options, patches, regather);
    if (!floor) continue;
    int seen = 0, beyond = 0;
    for (int v = 0; v < depth.camera.height; v += 4) {
      for (int u = 0; u < depth.camera.width; u += 4) {
        const float z = depth.at(u, v);
        if (std::isnan(z)) continue;
        ++seen;
        const Eigen::Vector3d p = z * PixelRay(depth.camera, u, v);
        // Depth noise grows with z^2: the floor's scatter, measured about
        // its centroid's depth, scaled to this point's.
        const double zr = p.z() / floor->centroid.z();
        const double limit = std::max(options.floor_tolerance_m, 3.0 * floor->rms * zr * zr);
        beyond += -floor->normal.dot(p - floor->centroid) > limit;
      }
    }
    if (seen > 0 && beyond <= options.floor_max_beyond_share * seen) return floor;
  }
  return std::nullopt;
}

// The frame's face proposals and its floor (FindFloor, with floor_check),
// found from the same patches before any of them proposes: the patches on
// the floor's plane propose nothing (unless judge_faces_on_floor), as each
// face on it would be a box reaching into the floor, never judged. Within
// half the box's smallest side of that plane (or the floor's tolerance, if
// less) a patch cannot be the top of a box lying on it.
FaceProposals FindFacesAndFloor(const DepthImage& depth, const DetectorOptions& options,
                                const FaceProposalOptions& face_options, const CancelToken* cancel,
                                internal::SharedLoops* helpers, std::optional<FloorPlane>* floor) {
  floor->reset();
  if (!options.floor_check) {
    return ProposeFromFaces(depth, options.box, face_options, cancel, helpers);
  }
  const double thinnest = std::min({options.box.l, options.box.b, options.box.h});
  return ProposeFromFaces(depth, options.box, face_options, cancel, helpers,
                          [&](const PlanarPatches& patches) -> std::optional<ExcludedPlane> {
                            *floor = FindFloor(depth, options, patches);
                            if (!*floor || options.judge_faces_on_floor) return std::nullopt;
                            ExcludedPlane plane;
                            plane.normal = (*floor)->normal;
                            plane.point = (*floor)->centroid;
                            plane.max_distance_m =
                                std::min(options.floor_tolerance_m, 0.5 * thinnest);
                            return plane;
                          });
}

// A box stands on something: amid the boxes of a layer found around it,
// their tops level with its own (DetectorOptions::max_below_neighbours_m),
// its bottom cannot lie far below theirs, in a hole of what they stand on.
// It takes two such neighbours, a layer: beside one box lying on another in
// a heap, a box on end stands as level with it; or one it lies flush
// against (DetectorOptions::flush_neighbour_is_layer). True when a box was
// taken out.
bool CheckStandsLevel(const DetectorOptions& options, std::vector<DetectedBox>* boxes,
                      std::vector<KeptReading>* readings,
                      std::vector<DeclinedCandidate>* declined) {
  constexpr int kLayerNeighbours = 2;
  const BoxDims& d = options.box;
  const double tol = options.max_below_neighbours_m;
  const std::vector<DetectedBox> all = *boxes;  // each judged against all
  auto height = [&](const DetectedBox& b) { return d[static_cast<int>(b.grasp_face) / 2]; };
  auto half_diagonal = [&](const DetectedBox& b) {
    const int n = static_cast<int>(b.grasp_face) / 2;
    return 0.5 * std::hypot(d[(n + 1) % 3], d[(n + 2) % 3]);
  };
  // A box read on a smaller face than the one it sits on (an end face
  // inside a carton's top) lies farther from that carton's neighbours than
  // its own face says: its neighbours are sought as far as the largest face
  // would reach.
  const double largest_half_diagonal =
      0.5 * std::max({std::hypot(d.l, d.b), std::hypot(d.l, d.h), std::hypot(d.b, d.h)});
  const double cos_parallel = std::cos(12.0 * M_PI / 180.0);
  return TakeOut(boxes, readings, declined, [&](size_t i) -> std::string {
    const DetectedBox& b = (*boxes)[i];
    int level = 0;
    double deepest = 0.0;
    for (size_t j = 0; j < all.size(); ++j) {
      if (j == i) continue;
      const DetectedBox& nb = all[j];
      const Eigen::Vector3d& n = nb.grasp_normal_camera;  // toward the camera
      if (b.grasp_normal_camera.dot(n) < cos_parallel) continue;
      const Eigen::Vector3d offset = b.grasp_centre_camera - nb.grasp_centre_camera;
      const double above = offset.dot(n);  // b's top above its neighbour's
      const double apart = (offset - above * n).norm();
      if (std::abs(above) > tol || apart > 1.15 * (largest_half_diagonal + half_diagonal(nb))) {
        continue;
      }
      const double below = height(b) - above - height(nb);  // b's bottom below nb's
      if (below <= tol) continue;
      // A neighbour that one of its sides lies against (touching, aligned:
      // SideAgainstKeptBox) is a layer on its own: boxes of a heap do not
      // meet flush along a whole side.
      bool flush = false;
      for (int s = 0; s < 4 && !flush && options.flush_neighbour_is_layer; ++s) {
        flush = internal::SideAgainstKeptBox(b.camera_T_box, b.grasp_face, d, s, {nb});
      }
      level += flush ? kLayerNeighbours : 1;
      deepest = std::max(deepest, below);
    }
    if (level < kLayerNeighbours) return "";
    return absl::StrFormat(
        "its top is level with %d boxes around it but its bottom would lie %.0f mm below theirs, "
        "in a hole: a box of another size?",
        level, 1000.0 * deepest);
  });
}

// The layer check (FaceProposalOptions::check_layer_tiling). A layer is
// trusted when a box ended by depth jumps on both axes of its face (a free
// side along each) is one of its tiles; on a trusted layer, a box that a
// seam, a tiling or a continuing side bounds and that is none of its tiles
// is taken out (a false seam in the middle of a face otherwise makes a
// box-wide strip of it: in the simulated cell such a box was picked 7 cm off
// its centre and hit the robot's pedestal). A layer nothing anchors (its
// outline may tile by chance, with boxes of another size in it) decides
// nothing. True when a box was taken out.
bool CheckLayers(const DepthImage& depth, const DetectorOptions& options,
                 const FaceProposals& faces, std::vector<DetectedBox>* boxes,
                 std::vector<KeptReading>* readings, std::vector<DeclinedCandidate>* declined) {
  const size_t n = boxes->size();
  std::vector<int> layer(n, -1);
  std::vector<bool> trusted(faces.layers.size(), false);
  std::vector<bool> tile(n, false);
  for (size_t i = 0; i < n; ++i) {
    const DetectedBox& b = (*boxes)[i];
    layer[i] =
        LayerUnder(faces, depth, b.grasp_centre_camera, b.grasp_normal_camera, options.faces);
    if (layer[i] < 0) continue;
    tile[i] = IsLayerTile(faces.layers[layer[i]], options.box, b.camera_T_box, options.faces);
    const std::array<SideKind, 4>& s = (*readings)[i].sides;
    const bool free_a = s[0] == SideKind::kFree || s[1] == SideKind::kFree;
    const bool free_b = s[2] == SideKind::kFree || s[3] == SideKind::kFree;
    if (tile[i] && free_a && free_b) trusted[layer[i]] = true;
  }
  return TakeOut(boxes, readings, declined, [&](size_t i) -> std::string {
    const std::array<SideKind, 4>& s = (*readings)[i].sides;
    const bool bounded_by_seams = std::any_of(s.begin(), s.end(), [](SideKind k) {
      return k == SideKind::kSeam || k == SideKind::kTiled || k == SideKind::kContinues;
    });
    if (layer[i] < 0 || !trusted[layer[i]] || tile[i] || !bounded_by_seams) return "";
    return absl::StrFormat(
        "its face lies on a layer that tiles with %d box faces (a box ended by depth jumps is "
        "one of them) and it is none of them: a strip of a face cut by a false seam, or a box "
        "turned across the layer",
        static_cast<int>(faces.layers[layer[i]].tiles.size()));
  });
}

// RefinementOptions::slat_gap_max_m: a box free on two opposite sides with
// its face's plane going on past a gap beyond each, where no other box
// found lies beyond either gap, is taken out: it is a board of a pallet's
// deck or a slat between two others (beyond a box lying flat among others
// in a heap, one of them is found). True when a box was taken out.
bool CheckGaps(const DetectorOptions& options, std::vector<DetectedBox>* boxes,
               std::vector<KeptReading>* readings, std::vector<DeclinedCandidate>* declined) {
  constexpr double kMargin = 0.015;
  const std::vector<DetectedBox> all = *boxes;  // each judged against all
  auto found_at = [&](const Eigen::Vector3d& p, size_t self) {
    for (size_t j = 0; j < all.size(); ++j) {
      if (j == self) continue;
      const Eigen::Vector3d local = all[j].camera_T_box.inverse() * p;
      if ((local.cwiseAbs() - 0.5 * options.box.vec()).maxCoeff() <= kMargin) return true;
    }
    return false;
  };
  // TakeOut compacts *boxes as it goes: `i` indexes the boxes as they were.
  return TakeOut(boxes, readings, declined, [&](size_t i) -> std::string {
    const std::array<std::optional<Eigen::Vector3d>, 4>& gap = (*readings)[i].past_gap;
    for (int pair = 0; pair < 4; pair += 2) {
      if (gap[pair] && gap[pair + 1] && !found_at(*gap[pair], i) && !found_at(*gap[pair + 1], i)) {
        return "it lies between two gaps in one flat surface with no box found beyond either (a "
               "pallet's deck board, a slat?)";
      }
    }
    return "";
  });
}

// Whether a box at `pose` was checked and kept in an earlier round of a
// check that judges other readings of it (`cleared`): not judged again.
bool WasCleared(const std::vector<Eigen::Isometry3d>& cleared, const Eigen::Isometry3d& pose) {
  return std::any_of(cleared.begin(), cleared.end(), [&](const Eigen::Isometry3d& c) {
    return (c.translation() - pose.translation()).norm() < 1e-4 &&
           c.linear().isApprox(pose.linear());
  });
}

// The end of such a check: the boxes `flagged` are taken out with
// `reason`, the others `checked` are cleared. True when one was taken out.
bool TakeOutFlagged(const std::vector<uint8_t>& checked, const std::vector<uint8_t>& flagged,
                    const char* reason, std::vector<DetectedBox>* boxes,
                    std::vector<KeptReading>* readings, std::vector<DeclinedCandidate>* declined,
                    std::vector<Eigen::Isometry3d>* cleared) {
  return TakeOut(boxes, readings, declined, [&](size_t i) -> std::string {
    if (!checked[i]) return "";
    if (flagged[i]) return reason;
    cleared->push_back((*boxes)[i].camera_T_box);
    return "";
  });
}

// DetectorOptions::turned_check: a box whose face reads as well turned a
// quarter at one of its measured corners is taken out. `cleared` holds the
// boxes checked and kept before (the checks run in rounds), not judged
// again. True when a box was taken out. The turned readings are judged on
// every thread, a box to a task (each judged alone, on the frame only: no
// box's verdict depends on another's), then taken out in order; on a
// pallet this check was a tenth to two fifths of the pose stage, on one
// core.
bool CheckTurnedReadings(const internal::HypothesisJudge& judge, const DetectorOptions& options,
                         std::vector<DetectedBox>* boxes, std::vector<KeptReading>* readings,
                         std::vector<DeclinedCandidate>* declined,
                         std::vector<Eigen::Isometry3d>* cleared) {
  auto measured = [](SideKind k) { return k == SideKind::kFree || k == SideKind::kSeam; };
  const int n = static_cast<int>(boxes->size());
  std::vector<uint8_t> checked(n, 0), turned(n, 0);
  for (int i = 0; i < n; ++i) {
    const std::array<SideKind, 4>& s = (*readings)[i].sides;
    if (std::all_of(s.begin(), s.end(), measured)) continue;
    checked[i] = !WasCleared(*cleared, (*boxes)[i].camera_T_box);
  }
  internal::ParallelForChunks(n, 1, options.num_threads, [&](int, int i, int) {
    if (!checked[i]) return;
    const DetectedBox& box = (*boxes)[i];
    for (const Eigen::Isometry3d& pose : internal::TurnedAtMeasuredCorners(
             box.camera_T_box, box.grasp_face, (*readings)[i].sides, options.box)) {
      if (judge.JudgeAlone(pose)) {
        turned[i] = 1;
        return;
      }
    }
  });
  return TakeOutFlagged(checked, turned,
                        "its face reads as well turned a quarter at one of its corners (a line in "
                        "a face taken for a seam?): declined as ambiguous",
                        boxes, readings, declined, cleared);
}

// DetectorOptions::paired_check: two boxes read side by side on one face
// whose faces together are another face of the box (internal::
// OneBoxForPair) are both taken out when that one box is judged a box too:
// two readings of one surface the evidence cannot separate, the line
// between them a carton's flap seam or tape. The one box's reading is then
// left to the rounds after (the layers' tiles, retake_outranked). `cleared`
// as for CheckTurnedReadings, a pair checked once.
bool CheckPairedReadings(const internal::HypothesisJudge& judge, const DetectorOptions& options,
                         std::vector<DetectedBox>* boxes, std::vector<KeptReading>* readings,
                         std::vector<DeclinedCandidate>* declined,
                         std::vector<Eigen::Isometry3d>* cleared) {
  const int n = static_cast<int>(boxes->size());
  struct Pair {
    int i, j;
    Eigen::Isometry3d one;
  };
  std::vector<Pair> pairs;
  std::vector<uint8_t> checked(n, 0), paired(n, 0);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (WasCleared(*cleared, (*boxes)[i].camera_T_box) &&
          WasCleared(*cleared, (*boxes)[j].camera_T_box)) {
        continue;
      }
      if (std::optional<Eigen::Isometry3d> one = internal::OneBoxForPair(
              (*boxes)[i], (*boxes)[j], options.box, options.acceptance.extent_tolerance_m)) {
        pairs.push_back({i, j, *one});
        checked[i] = checked[j] = 1;
      }
    }
  }
  if (pairs.empty()) return false;
  std::vector<uint8_t> one_is_a_box(pairs.size(), 0);
  internal::ParallelForChunks(
      static_cast<int>(pairs.size()), 1, options.num_threads,
      [&](int, int p, int) { one_is_a_box[p] = judge.JudgeAlone(pairs[p].one).has_value(); });
  for (size_t p = 0; p < pairs.size(); ++p) {
    if (one_is_a_box[p]) paired[pairs[p].i] = paired[pairs[p].j] = 1;
  }
  return TakeOutFlagged(checked, paired,
                        "with the box beside it, its face is one face of a box on another side, "
                        "judged a box too (a flap seam or tape taken for a seam?): declined as "
                        "ambiguous",
                        boxes, readings, declined, cleared);
}

// DetectorOptions::shifted_check: a box seamed on both sides of an axis,
// with fewer than two free sides, whose face shifted half its width along
// that axis is judged a box with more free sides, is taken out; a shifted
// reading on another box kept is not judged. `cleared` as for
// CheckTurnedReadings; the shifted readings judged on every thread, a box
// to a task.
bool CheckShiftedReadings(const internal::HypothesisJudge& judge, const DetectorOptions& options,
                          std::vector<DetectedBox>* boxes, std::vector<KeptReading>* readings,
                          std::vector<DeclinedCandidate>* declined,
                          std::vector<Eigen::Isometry3d>* cleared) {
  auto free_sides = [](const std::array<SideKind, 4>& s) {
    return static_cast<int>(std::count(s.begin(), s.end(), SideKind::kFree));
  };
  const int n = static_cast<int>(boxes->size());
  std::vector<uint8_t> checked(n, 0), shifted(n, 0);
  for (int i = 0; i < n; ++i) {
    const std::array<SideKind, 4>& s = (*readings)[i].sides;
    const bool seamed_a = s[0] == SideKind::kSeam && s[1] == SideKind::kSeam;
    const bool seamed_b = s[2] == SideKind::kSeam && s[3] == SideKind::kSeam;
    if ((!seamed_a && !seamed_b) || free_sides(s) >= 2) continue;
    checked[i] = !WasCleared(*cleared, (*boxes)[i].camera_T_box);
  }
  internal::ParallelForChunks(n, 1, options.num_threads, [&](int, int i, int) {
    if (!checked[i]) return;
    const DetectedBox& box = (*boxes)[i];
    const std::array<SideKind, 4>& s = (*readings)[i].sides;
    const int axis_n = static_cast<int>(box.grasp_face) / 2;
    for (int side_pair = 0; side_pair < 2; ++side_pair) {
      if (s[2 * side_pair] != SideKind::kSeam || s[2 * side_pair + 1] != SideKind::kSeam) continue;
      const int axis = side_pair == 0 ? (axis_n + 1) % 3 : (axis_n + 2) % 3;
      const Eigen::Vector3d along = box.camera_T_box.linear().col(axis);
      for (const double sign : {1.0, -1.0}) {
        Eigen::Isometry3d pose = box.camera_T_box;
        pose.translation() += sign * 0.5 * options.box[axis] * along;
        // Where another box kept lies, the shifted reading contradicts it:
        // on a layer found right, every inner box's shift (most of the
        // check's cost) stops here.
        const bool on_kept = std::any_of(boxes->begin(), boxes->end(), [&](const DetectedBox& k) {
          return &k != &box && internal::BoxesOverlap(k.camera_T_box, pose, options.box,
                                                      options.acceptance.overlap_margin_m);
        });
        if (on_kept) continue;
        const std::optional<internal::Candidate> c = judge.JudgeAlone(pose);
        if (c && c->refinement.free_sides > free_sides(s)) {
          shifted[i] = 1;
          return;
        }
      }
    }
  });
  return TakeOutFlagged(checked, shifted,
                        "its face shifted half its width across its two seams is a box ended by "
                        "more free sides (lines inside two faces taken for seams?): declined",
                        boxes, readings, declined, cleared);
}

// The strongest declined hypotheses: none that overlaps a returned box (a
// variant of it) or a stronger declined one.
std::vector<DeclinedCandidate> StrongestDeclined(std::vector<DeclinedCandidate> all,
                                                 const std::vector<DetectedBox>& boxes,
                                                 const DetectorOptions& o) {
  std::stable_sort(
      all.begin(), all.end(),
      [](const DeclinedCandidate& a, const DeclinedCandidate& b) { return a.score > b.score; });
  std::vector<DeclinedCandidate> out;
  for (DeclinedCandidate& d : all) {
    if (static_cast<int>(out.size()) >= o.max_declined) break;
    auto overlaps = [&](const Eigen::Isometry3d& pose) {
      return internal::BoxesOverlap(pose, d.camera_T_box, o.box, o.acceptance.overlap_margin_m);
    };
    if (std::any_of(boxes.begin(), boxes.end(),
                    [&](const DetectedBox& b) { return overlaps(b.camera_T_box); }) ||
        std::any_of(out.begin(), out.end(),
                    [&](const DeclinedCandidate& c) { return overlaps(c.camera_T_box); })) {
      continue;
    }
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace

namespace {

// Whether the frame's grey image varies by at least `min_contrast` levels
// (every 4th pixel of every 4th row read).
bool ColourShowsSomething(const DepthImage& depth, double min_contrast) {
  if (!depth.has_grey()) return false;
  float lo = 255.0f, hi = 0.0f;
  for (int v = 0; v < depth.camera.height; v += 4) {
    for (int u = 0; u < depth.camera.width; u += 4) {
      lo = std::min(lo, depth.grey_at(u, v));
      hi = std::max(hi, depth.grey_at(u, v));
    }
  }
  return hi - lo >= min_contrast;
}

}  // namespace

void DeriveGeometryParameters(double z, double focal_px, DetectorOptions* o) {
  const DetectorOptions defaults;
  const double smallest = std::min({o->box.l, o->box.b, o->box.h});
  double r = std::max(0.02, z > 0.0 && focal_px > 0.0 ? 6.0 * z / focal_px : 0.0);
  r = std::min(r, 0.35 * smallest);
  // To half a millimetre: finer is below the depth noise, and a box whose
  // rule lands within a hair of the default (a brick: 0.35 x 57 mm) keeps it.
  r = std::round(r * 2000.0) / 2000.0;
  if (o->edge_points.radius_m == defaults.edge_points.radius_m) {
    o->edge_points.radius_m = r;
    if (o->segments.gap_m == defaults.segments.gap_m) o->segments.gap_m = r;
  }
  if (o->segments.ransac_threshold_m == defaults.segments.ransac_threshold_m) {
    o->segments.ransac_threshold_m = r / 2.0;
  }
  if (o->clubbing.meet_distance_m == defaults.clubbing.meet_distance_m) {
    o->clubbing.meet_distance_m = r / 2.0;
  }
  if (o->evidence.outline_margin_m == defaults.evidence.outline_margin_m) {
    o->evidence.outline_margin_m = r / 2.0;
  }
  // The planar patches' normal window: a wider one (7 x 7 cells) where it
  // spans at most 0.8 of the box's smallest side at depth z. A noisy
  // sensor at 2 m (stereo: ~7 mm) makes half the cells of a 5 x 5 window
  // on a flat face look curved, so faces came out in pieces; a brick's
  // faces are too narrow for it.
  PlanarPatchOptions& patches = o->faces.patches;
  if (patches.window_cells == defaults.faces.patches.window_cells && z > 0.0 && focal_px > 0.0 &&
      7.0 * patches.step_px <= 0.8 * smallest * focal_px / z) {
    patches.window_cells = 3;
  }
}

absl::Status AcceptanceOptions::Validate() const {
  for (absl::Status s : {
           CheckRange("acceptance.min_support", min_support, 0.0, 1.0),
           CheckRange("acceptance.min_grasp_support", min_grasp_support, 0.0, 1.0),
           CheckRange("acceptance.max_grasp_occluded", max_grasp_occluded, 0.0, 1.0),
           CheckRange("acceptance.max_occluded", max_occluded, 0.0, 1.0),
           CheckRange("acceptance.max_see_through", max_see_through, 0.0, 1.0),
           CheckRange("acceptance.unseen_longer_see_through", unseen_longer_see_through, 0.0, 1.0),
           CheckRange("acceptance.min_grasp_pixels", min_grasp_pixels, 1, 1'000'000),
           CheckPositive("acceptance.extent_tolerance_m", extent_tolerance_m, 1.0),
           CheckRange("acceptance.max_short_both_axes_m", max_short_both_axes_m, 0.0, 1.0),
           CheckRange("acceptance.max_grasp_view_angle_deg", max_grasp_view_angle_deg, 0.0, 90.0),
           CheckRange("acceptance.border_margin_px", border_margin_px, 0.0, 1000.0),
           CheckRange("acceptance.leaving_view_free_axes", leaving_view_free_axes, 0, 2),
           CheckPositive("acceptance.min_in_view_share", min_in_view_share, 1.0),
           CheckRange("acceptance.max_out_of_view_share", max_out_of_view_share, 0.0, 0.99),
           CheckRange("acceptance.overlap_margin_m", overlap_margin_m, 0.0, 1.0),
           CheckRange("acceptance.settled_overlap_margin_m", settled_overlap_margin_m, 0.0, 1.0),
       }) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status DetectorOptions::Validate() const {
  if (absl::Status s = box.Validate(); !s.ok()) return s;
  for (absl::Status s : {edge_points.Validate(), segments.Validate(), clubbing.Validate(),
                         pose.Validate(), refinement.Validate(), evidence.Validate(),
                         acceptance.Validate(), faces.Validate(), layer_plane.Validate(),
                         layer_turn.Validate(), floor_rest.Validate(), edge_pairs.Validate()}) {
    if (!s.ok()) return s;
  }
  if (empty_frame_window_cells < 0 || empty_frame_window_cells > 8) {
    return absl::InvalidArgumentError(
        absl::StrCat("empty_frame_window_cells=", empty_frame_window_cells, " is outside [0, 8]"));
  }
  if (!(floor_tolerance_m > 0.0 && floor_tolerance_m <= 0.5)) {
    return absl::InvalidArgumentError(
        absl::StrCat("floor_tolerance_m=", floor_tolerance_m, " is outside (0, 0.5]"));
  }
  if (!(floor_max_beyond_share >= 0.0 && floor_max_beyond_share <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("floor_max_beyond_share=", floor_max_beyond_share, " is outside [0, 1]"));
  }
  if (!(max_below_neighbours_m >= 0.0 && max_below_neighbours_m <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_below_neighbours_m=", max_below_neighbours_m, " is outside [0, 1]"));
  }
  if (!(floor_min_area_m2 > 0.0 && floor_min_area_m2 <= 100.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("floor_min_area_m2=", floor_min_area_m2, " is outside (0, 100]"));
  }
  if (size_tolerance_m && !(*size_tolerance_m > 0.0 && *size_tolerance_m <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("size_tolerance_m=", *size_tolerance_m, " is outside (0, 0.1]"));
  }
  if (!(edge_lattice_radius_px >= 0.0 && edge_lattice_radius_px <= 100.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("edge_lattice_radius_px=", edge_lattice_radius_px, " is outside [0, 100]"));
  }
  if (max_declined < 0 || max_declined > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_declined=", max_declined, " is outside [0, 1000]"));
  }
  if (neighbour_steps_past_declined < 0 || neighbour_steps_past_declined > 4) {
    return absl::InvalidArgumentError(absl::StrCat(
        "neighbour_steps_past_declined=", neighbour_steps_past_declined, " is outside [0, 4]"));
  }
  if (camera) {
    if (absl::Status s = camera->Validate(); !s.ok()) return s;
  }
  if (num_threads < 1 || num_threads > 256) {
    return absl::InvalidArgumentError(
        absl::StrCat("num_threads=", num_threads, " is outside [1, 256]"));
  }
  if (max_points < 1) return absl::InvalidArgumentError("max_points must be positive");
  return absl::OkStatus();
}

void SetEdgeRadius(double radius_m, DetectorOptions* options) {
  options->edge_points.radius_m = radius_m;
  options->segments.gap_m = radius_m;
}

void UseFrameCamera(const std::optional<CameraIntrinsics>& frame_camera, DetectorOptions* options) {
  if (frame_camera) options->camera = frame_camera;
}

namespace {

// The frame as the stages read it: the input sanitized (and an unorganized
// single-view cloud laid onto the camera's pixel grid), its camera, its depth
// image, and the options with what the frame's geometry derives. Not movable:
// `work` points into it.
struct PreparedFrame {
  PreparedFrame() = default;
  PreparedFrame(const PreparedFrame&) = delete;
  PreparedFrame& operator=(const PreparedFrame&) = delete;

  DetectorOptions options;
  CameraIntrinsics camera;
  PointCloud sanitized, projected;  // storage for `work` when it is neither the input
  const PointCloud* work = nullptr;
  DepthImage depth;
  bool too_few_points = false;  // an organized frame with too few valid points to hold a box
};

// Phase 1: checks the input, sanitizes it, finds the camera and the depth
// image, and derives the geometry parameters.
absl::Status PrepareFrame(const PointCloud& input, const DetectorOptions& options_in,
                          PreparedFrame* f) {
  if (absl::Status s = options_in.Validate(); !s.ok()) return s;
  if (absl::Status s = input.Validate(); !s.ok()) return s;
  const PointCloud& cloud = SanitizeCloud(input, &f->sanitized);
  if (cloud.size() > static_cast<size_t>(options_in.max_points)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "cloud has ", cloud.size(), " points, above the limit of ", options_in.max_points));
  }
  DetectorOptions& options = f->options;
  options = options_in;
  options.edge_points.num_threads = options.num_threads;
  // With face proposals, one thread finds the planar patches while the
  // others fit the segments, and then helps them (FindSegments).
  options.segments.num_threads = options.num_threads;

  f->camera = options.camera.value_or(CameraIntrinsics{});
  if (cloud.organized()) {
    absl::StatusOr<CameraIntrinsics> k = EstimateIntrinsics(cloud);
    if (!k.ok()) {
      f->too_few_points = true;
      return absl::OkStatus();
    }
    if (absl::Status s = k->Validate(); !s.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("the organized cloud's points imply implausible ", s.message()));
    }
    f->camera = *k;
  }
  // An unorganized cloud costs its camera's pixel grid (the projection and
  // the depth image), not its points: 20 000 points with a 16384 x 16384
  // camera took 16 s and 4 GB before a deadline could stop it.
  if (!cloud.organized() &&
      static_cast<int64_t>(f->camera.width) * f->camera.height > kMaxUnorganizedGridPixels) {
    return absl::InvalidArgumentError(absl::StrCat(
        "intrinsics image size ", f->camera.width, " x ", f->camera.height, " is above the ",
        kMaxUnorganizedGridPixels,
        " pixels an unorganized cloud is laid onto: give the camera's own image size"));
  }
  // A single-view unorganized cloud is laid back onto the camera's pixel
  // grid, so it takes the same (fast, shadow-aware) path as a frame.
  // A cloud that is not in a camera's frame (a merged scan, an object
  // model) mostly falls outside the image: it keeps the k-d tree path.
  bool project = !cloud.organized() && options.project_unorganized;
  if (project) {
    f->projected = OrganizeByProjection(cloud, f->camera);
    PointCloud in_range;  // the projected frame gets a camera's depth range
    if (&SanitizeCloud(f->projected, &in_range) != &f->projected) {
      f->projected = std::move(in_range);
    }
    const auto valid = [](const std::vector<Eigen::Vector3f>& xyz) {
      return std::count_if(xyz.begin(), xyz.end(), PointCloud::IsValid);
    };
    project = 2 * valid(f->projected.xyz) >= valid(cloud.xyz);
  }
  if (project) {
    f->work = &f->projected;
  } else {
    f->work = &cloud;  // the input or f->sanitized
  }
  f->depth = MakeDepthImage(*f->work, f->camera);
  const double median_z = MedianDepth(f->depth);
  if (options.parameters_from_geometry) DeriveGeometryParameters(median_z, f->camera.fx, &options);
  // Without a colour image that shows something (a grey image of one
  // level is none: colour is evidence, never a switch) the judge cannot
  // tell a seam from an active stereo camera's noise in the depth, and the
  // corners the along-view allowance adds propose readings of a seamless
  // layer it cannot separate (eight generated depth-only sets: 7 wrong
  // boxes more on stereo pallets, against 9 heap boxes more): the paper's
  // sphere, unless the caller set the factor.
  if (!ColourShowsSomething(f->depth, options.refinement.colour_seams.min_contrast) &&
      options.clubbing.meet_along_view_factor == ClubbingOptions{}.meet_along_view_factor) {
    options.clubbing.meet_along_view_factor = 1.0;
  }
  if (options.size_tolerance_m) ApplySizeTolerance(*options.size_tolerance_m, &options);
  // Nothing else judges the turned reading of a face hidden on two sides.
  if (!options.turned_check) options.acceptance.turned_hidden_corner_to_check = false;
  if (options.edge_lattice_radius_px > 0.0) {
    const double radius_px =
        median_z > 0.0 ? options.edge_points.radius_m * f->camera.fx / median_z : 0.0;
    // Clamped before the cast: a tiny edge_lattice_radius_px (valid, > 0)
    // makes the ratio too large for an int (found by detect_request_fuzzer).
    const double lattice = radius_px / options.edge_lattice_radius_px;
    options.edge_points.lattice_px =
        std::isfinite(lattice)
            ? static_cast<int>(std::clamp(lattice, 1.0, static_cast<double>(kMaxEdgeLattice)))
            : 1;
  }
  return absl::OkStatus();
}

// Phase 2: the edge points, their segments and corners (the paper's
// stages), and beside them the planar patches and their tilings.
absl::Status FindEdgesAndFaces(const PreparedFrame& f, const CancelToken& cancel, Detection* det,
                               SegmentGroups* groups, FaceProposals* faces,
                               std::optional<FloorPlane>* floor) {
  const DetectorOptions& options = f.options;
  Clock::time_point t0 = Clock::now();
  absl::StatusOr<EdgePoints> edges =
      DetectEdgePoints(*f.work, options.edge_points, f.camera.fx, &cancel);
  if (!edges.ok()) return edges.status();
  if (absl::Status s = cancel.Check("the edge points"); !s.ok()) return s;
  det->edge_points = edges->points;
  det->timings.edge_points_ms = MsSince(t0);

  // The planar patches and their tilings need only the depth image: they
  // are found on a thread of their own while the edge points become
  // segments and corners. Done with them, that thread helps fit the
  // segments (their RANSAC iterations are shared loops), so neither stage
  // waits on the other. Beyond two threads, the others help from the start.
  // The other way round too: done with the segments, the other threads
  // help tile the patches, one patch at a time (on pallets the patches take
  // twice as long as the segments).
  internal::SharedLoops shared, face_loops;
  const bool share = options.face_proposals && options.num_threads > 1;
  {
    std::jthread faces_thread;  // joined at the end of this block, on every path
    if (options.face_proposals) {
      faces_thread = std::jthread([&] {
        const Clock::time_point t_faces = Clock::now();
        *faces = FindFacesAndFloor(f.depth, options, options.faces, &cancel,
                                   share ? &face_loops : nullptr, floor);
        det->timings.faces_ms = MsSince(t_faces);
        face_loops.Close();
        if (share) shared.Help();
      });
    }
    std::vector<std::jthread> helpers;
    for (int t = 2; share && t < options.num_threads; ++t) {
      helpers.emplace_back([&] {
        shared.Help();
        face_loops.Help();
      });
    }
    t0 = Clock::now();
    absl::StatusOr<std::vector<EdgeSegment>> segments =
        FitEdgeSegments(det->edge_points, options.segments, share ? &shared : nullptr, &cancel);
    shared.Close();
    det->timings.edge_segments_ms = MsSince(t0);
    if (share) face_loops.Help();
    helpers.clear();  // joined
    if (!segments.ok()) return segments.status();
    det->segments = *std::move(segments);
  }
  if (absl::Status s = cancel.Check("the edge segments and planar patches"); !s.ok()) return s;

  t0 = Clock::now();
  absl::StatusOr<SegmentGroups> clubbed = ClubSegments(det->segments, options.clubbing);
  if (!clubbed.ok()) return clubbed.status();
  *groups = *std::move(clubbed);
  det->corners = groups->corners;
  det->timings.clubbing_ms = MsSince(t0);
  return absl::OkStatus();
}

// Phase 3: every corner proposes the poses its two edges' lengths allow,
// refined with the other corners of its segments' group (the paper's
// Section 3.4).
void ProposeFromCorners(const Detection& det, const SegmentGroups& groups,
                        const DetectorOptions& options, internal::HypothesisJudge* judge) {
  std::vector<int> group_of(det.segments.size(), -1);
  for (size_t g = 0; g < groups.groups.size(); ++g) {
    for (int s : groups.groups[g]) group_of[s] = static_cast<int>(g);
  }
  std::vector<std::vector<Eigen::Vector3d>> group_corners(groups.groups.size());
  for (const Corner& c : det.corners) {
    group_corners[group_of[c.segment_a]].push_back(c.position.cast<double>());
  }
  for (const Corner& c : det.corners) {
    const EdgeSegment& sa = det.segments[c.segment_a];
    const EdgeSegment& sb = det.segments[c.segment_b];
    const Eigen::Vector3d p1 = c.position.cast<double>();
    const Eigen::Vector3d fa = (c.a_at_end1 ? sa.end2 : sa.end1).cast<double>();
    const Eigen::Vector3d fb = (c.b_at_end1 ? sb.end2 : sb.end1).cast<double>();
    const double la = (fa - p1).norm(), lb = (fb - p1).norm();
    if (la < 1e-3 || lb < 1e-3) continue;
    for (const AxisAssignment& as :
         CheapestReadings(MatchEdgeLengths(la, lb, options.box, options.pose),
                          options.pose.max_readings_per_corner)) {
      Eigen::Isometry3d pose = PoseFromCorner(p1, fa - p1, fb - p1, as, options.box);
      const int corners = 1 + RefineWithCorners(group_corners[group_of[c.segment_a]], options.box,
                                                options.pose, &pose);
      judge->Propose(pose, corners, {c.segment_a, c.segment_b});
    }
  }
}

// Phase 4: the judge's verdicts become boxes. Best first; a box overlapping
// an accepted one is the same box or a contradiction, and is dropped. Each
// accepted box proposes its neighbours, which are judged the same way and
// may propose theirs.
class BoxAcceptance {
 public:
  BoxAcceptance(const DetectorOptions& options, const CancelToken& cancel,
                internal::HypothesisJudge* judge, Detection* det)
      : options_(options), cancel_(cancel), judge_(judge), det_(det) {}

  bool OverlapsKept(const Eigen::Isometry3d& pose) const {
    return std::any_of(det_->boxes.begin(), det_->boxes.end(), [&](const DetectedBox& kept) {
      return internal::BoxesOverlap(kept.camera_T_box, pose, options_.box,
                                    options_.acceptance.overlap_margin_m);
    });
  }

  // Judges what is queued, accepts, and judges what the accepted propose,
  // until nothing is left (or the token stops).
  void AcceptAll() {
    std::vector<internal::Candidate> pending = judge_->Evaluate(options_.num_threads, det_->boxes);
    std::vector<internal::HypothesisJudge::SteppingStone> stones = judge_->TakeSteppingStones();
    while ((!pending.empty() || !stones.empty() || judge_->Queued()) && !cancel_.Stopped()) {
      // The reading whose face ends in more free borders goes first, then
      // the higher score: a free border is measured, a seam or a tiling is
      // inferred (two boxes on end side by side have a lying box's outline,
      // and a Kinect's noise can make a seam of nothing in a face).
      std::stable_sort(pending.begin(), pending.end(),
                       [](const internal::Candidate& a, const internal::Candidate& b) {
                         if (a.refinement.free_sides != b.refinement.free_sides) {
                           return a.refinement.free_sides > b.refinement.free_sides;
                         }
                         return a.box.score > b.box.score;
                       });
      for (internal::Candidate& c : pending) {
        if (!OverlapsKept(c.box.camera_T_box)) {
          Keep(c);
        } else {
          outranked_.push_back(c.box.camera_T_box);
        }
      }
      // A declined neighbour's neighbours (DetectorOptions::
      // neighbour_steps_past_declined): the chain goes on past a seam missed.
      for (const internal::HypothesisJudge::SteppingStone& stone : stones) {
        for (const Eigen::Isometry3d& pose :
             NeighbourHypotheses(stone.box, options_.box, options_.neighbour_gap_m)) {
          if (!OverlapsKept(pose)) judge_->ProposePastDeclined(pose, stone.steps);
        }
      }
      pending = judge_->Evaluate(options_.num_threads, det_->boxes);
      stones = judge_->TakeSteppingStones();
    }
  }

  // Pairs that end each other (AcceptPairs), each with what it proposes,
  // until no pair is left: after every other hypothesis (two boxes that
  // vouch for each other are less sure than one its own sides end).
  void AcceptPairsAndTheirs() {
    while (!cancel_.Stopped() && AcceptPairs()) AcceptAll();
  }

  // The readings of each det->boxes entry, for the plausibility checks.
  std::vector<KeptReading>* readings() { return &readings_; }

  // Hypotheses accepted but not kept, a box kept before them in the way,
  // which no box kept now overlaps (a plausibility check took it out):
  // each judged again from where it was refined, with the boxes kept now,
  // and kept when it passes, in the order they were outranked. True when
  // one was kept.
  bool KeepOutrankedNowFree() {
    bool any = false;
    std::vector<Eigen::Isometry3d> still;
    for (const Eigen::Isometry3d& pose : std::exchange(outranked_, {})) {
      if (cancel_.Stopped()) break;
      if (OverlapsKept(pose)) {
        still.push_back(pose);
        continue;
      }
      const std::optional<internal::Candidate> c = judge_->JudgeAlone(pose, det_->boxes);
      if (c && !OverlapsKept(c->box.camera_T_box)) {
        Keep(*c);
        any = true;
      }
    }
    outranked_.insert(outranked_.end(), still.begin(), still.end());
    return any;
  }

 private:
  // Keeps an accepted candidate; it proposes its neighbours.
  void Keep(const internal::Candidate& c) {
    det_->boxes.push_back(c.box);
    readings_.push_back({c.refinement.sides, c.refinement.past_gap});
    if (options_.propagate_to_neighbours) {
      for (const Eigen::Isometry3d& pose : NeighbourHypotheses(
               c.box, options_.box, options_.neighbour_gap_m, options_.neighbours_a_layer_down)) {
        judge_->ProposeNeighbour(pose, c.chained);
      }
    }
  }

  // A declined candidate as a kept box would be (its grasp face's centre
  // and normal set), for SideAgainstKeptBox.
  DetectedBox AsKept(const internal::Candidate& c) const {
    DetectedBox b = c.box;
    const Eigen::Vector3d n = BoxFaceNormal(b.grasp_face);
    const int axis = static_cast<int>(b.grasp_face) / 2;
    b.grasp_normal_camera = b.camera_T_box.linear() * n;
    b.grasp_centre_camera = b.camera_T_box * (n * options_.box[axis] / 2.0);
    return b;
  }

  // True when the outline of the two faces together (a's face and b's,
  // side by side across a's side `side_a`) tiles with two faces of the box
  // or fewer one way only (TilingsOf; a finer tiling needs more seams the
  // depth does not show, as the face tiles' fewest-tiles rule has it): two
  // bricks side by side along their short sides make a square that tiles
  // as well with the two turned a quarter, and nothing in the depth says
  // which.
  bool PairTilesOneWay(const internal::Candidate& a, int side_a,
                       const internal::Candidate& b) const {
    const int n = static_cast<int>(a.box.grasp_face) / 2;
    const int here = side_a < 2 ? (n + 1) % 3 : (n + 2) % 3;
    const int other = side_a < 2 ? (n + 2) % 3 : (n + 1) % 3;
    const Eigen::Vector3d axis = a.box.camera_T_box.linear().col(here);
    const double span =
        std::abs((b.box.camera_T_box.translation() - a.box.camera_T_box.translation()).dot(axis)) +
        options_.box[here];
    const std::vector<FaceTiling> tilings =
        TilingsOf(span, options_.box[other], options_.box, options_.faces);
    return std::count_if(tilings.begin(), tilings.end(),
                         [](const FaceTiling& t) { return t.tiles() <= 2; }) == 1;
  }

  // A side of the candidate's face ends in a seam or a whole tile: it lies
  // in a layer of touching boxes. A pair ended by free sides all round is
  // one flat thing twice the box's size as much as two boxes (a deck
  // board between a pallet's edge and the layer standing on it).
  static bool Seamed(const internal::Candidate& c) {
    const auto& sides = c.refinement.sides;
    return std::any_of(sides.begin(), sides.end(),
                       [](SideKind k) { return k == SideKind::kSeam || k == SideKind::kTiled; });
  }

  // Hypotheses declined only for one side on flat whose flat sides lie
  // against each other's face (AcceptanceOptions::pairs_end_each_other):
  // each judged again with the other taken as kept; both kept when both
  // pass. True when a pair was kept.
  bool AcceptPairs() {
    std::vector<internal::Candidate> singles = judge_->TakeOneSideOnFlat();
    std::erase_if(singles,
                  [&](const internal::Candidate& c) { return OverlapsKept(c.box.camera_T_box); });
    auto flat_side = [](const internal::Candidate& c) {
      const auto& sides = c.refinement.sides;
      return static_cast<int>(std::find(sides.begin(), sides.end(), SideKind::kContinues) -
                              sides.begin());
    };
    bool any = false;
    for (size_t i = 0; i < singles.size(); ++i) {
      for (size_t j = i + 1; j < singles.size(); ++j) {
        const internal::Candidate &a = singles[i], &b = singles[j];
        if (OverlapsKept(a.box.camera_T_box) || OverlapsKept(b.box.camera_T_box)) continue;
        const DetectedBox ka = AsKept(a), kb = AsKept(b);
        if (!internal::SideAgainstKeptBox(a.box.camera_T_box, a.box.grasp_face, options_.box,
                                          flat_side(a), {kb}) ||
            !internal::SideAgainstKeptBox(b.box.camera_T_box, b.box.grasp_face, options_.box,
                                          flat_side(b), {ka})) {
          continue;
        }
        if (!PairTilesOneWay(a, flat_side(a), b) || !(Seamed(a) || Seamed(b))) continue;
        std::vector<DetectedBox> with = det_->boxes;
        with.push_back(kb);
        const std::optional<internal::Candidate> ja = judge_->JudgeAlone(a.box.camera_T_box, with);
        if (!ja) continue;
        with.back() = ka;
        const std::optional<internal::Candidate> jb = judge_->JudgeAlone(b.box.camera_T_box, with);
        if (!jb || OverlapsKept(ja->box.camera_T_box) || OverlapsKept(jb->box.camera_T_box) ||
            internal::BoxesOverlap(ja->box.camera_T_box, jb->box.camera_T_box, options_.box,
                                   options_.acceptance.overlap_margin_m)) {
          continue;
        }
        Keep(*ja);
        Keep(*jb);
        any = true;
      }
    }
    return any;
  }

  const DetectorOptions& options_;
  const CancelToken& cancel_;
  internal::HypothesisJudge* const judge_;
  Detection* const det_;
  std::vector<KeptReading> readings_;
  // Accepted but not kept: a box kept before each overlapped it
  // (KeepOutrankedNowFree).
  std::vector<Eigen::Isometry3d> outranked_;
};

// A face proposal on the floor itself: every corner of the box at most
// 1.5 cm above the floor's plane and the deepest more than the floor's
// tolerance and 2 cm beyond it. Refinement fits the face to the depth
// there, the floor, so the box stays through it and is declined when
// judged ("would reach ... into the floor"): a planar patch of the floor
// tiles into box faces, and a noisy one's seam lines frame hundreds.
bool FaceOnTheFloor(const Eigen::Isometry3d& pose, const BoxDims& dims, const FloorPlane& floor,
                    double tolerance_m) {
  const internal::CornerHeights h =
      internal::CornerHeightsAbove(pose, dims, floor.normal, floor.centroid);
  return h.highest <= 0.015 && h.lowest < -(tolerance_m + 0.02);
}

// The faces between parallel edges (edge_pair_faces.h), queued after the
// face tiles and judged in one batch with them: the ranking picks between a
// pair's reading and a tiling's, and where both propose one pose (the queue
// keeps the first) it is judged as the tile it also is.
void ProposeEdgePairs(const std::vector<EdgePairFace>& pairs, const BoxAcceptance& acceptance,
                      internal::HypothesisJudge* judge) {
  for (const EdgePairFace& pair : pairs) {
    if (!acceptance.OverlapsKept(pair.camera_T_box)) {
      judge->Propose(pair.camera_T_box, 0, {pair.segment_a, pair.segment_b});
    }
  }
}

// Phase 5: the face tiles (after the corner hypotheses: a tile on a box
// already found is not judged again), then the plausibility checks; where
// they took a box out, the layers' own tiles get their turn, and what that
// accepts is checked again (a few rounds, then a last check with nothing
// proposed).
void AcceptFaceTilesAndCheck(const PreparedFrame& f, const FaceProposals& faces,
                             const std::vector<EdgePairFace>& pairs,
                             const std::optional<FloorPlane>& floor,
                             internal::HypothesisJudge* judge, BoxAcceptance* acceptance,
                             Detection* det, std::vector<DeclinedCandidate>* declined) {
  const DetectorOptions& options = f.options;
  auto worth_judging = [&](const Eigen::Isometry3d& pose) {
    return !acceptance->OverlapsKept(pose) &&
           !(floor && !options.judge_faces_on_floor &&
             FaceOnTheFloor(pose, options.box, *floor, options.floor_tolerance_m));
  };
  for (const Eigen::Isometry3d& pose : faces.poses) {
    if (worth_judging(pose)) judge->Propose(pose, 0, {}, true);
  }
  ProposeEdgePairs(pairs, *acceptance, judge);
  for (const DeclinedCandidate& d : faces.declined) {
    declined->push_back(d);
    declined->back().score =
        MeasureBox(f.depth, d.camera_T_box, options.box, options.evidence).support();
  }
  acceptance->AcceptAll();
  acceptance->AcceptPairsAndTheirs();
  std::vector<Eigen::Isometry3d> cleared;          // CheckTurnedReadings
  std::vector<Eigen::Isometry3d> cleared_shifted;  // CheckShiftedReadings
  std::vector<Eigen::Isometry3d> cleared_paired;   // CheckPairedReadings
  auto check = [&] {
    const bool layer_removed =
        options.faces.check_layer_tiling &&
        CheckLayers(f.depth, options, faces, &det->boxes, acceptance->readings(), declined);
    const bool level_removed =
        options.max_below_neighbours_m > 0.0 &&
        CheckStandsLevel(options, &det->boxes, acceptance->readings(), declined);
    const bool gaps_removed = options.refinement.slat_gap_max_m > 0.0 &&
                              CheckGaps(options, &det->boxes, acceptance->readings(), declined);
    const bool turned_removed =
        options.turned_check && CheckTurnedReadings(*judge, options, &det->boxes,
                                                    acceptance->readings(), declined, &cleared);
    const bool shifted_removed =
        options.shifted_check &&
        CheckShiftedReadings(*judge, options, &det->boxes, acceptance->readings(), declined,
                             &cleared_shifted);
    const bool paired_removed =
        options.paired_check &&
        CheckPairedReadings(*judge, options, &det->boxes, acceptance->readings(), declined,
                            &cleared_paired);
    return layer_removed || level_removed || gaps_removed || turned_removed || shifted_removed ||
           paired_removed;
  };
  for (int round = 0; round < 3 && check(); ++round) {
    for (const LayerTiles& layer : faces.layers) {
      for (const Eigen::Isometry3d& tile : layer.tiles) {
        if (worth_judging(tile)) judge->Propose(tile, 0, {}, true);
      }
    }
    acceptance->AcceptAll();
    // What a box taken out had outranked may be kept now.
    if (options.retake_outranked && acceptance->KeepOutrankedNowFree()) acceptance->AcceptAll();
  }
  check();
}

}  // namespace

namespace {

// Phases 3 to 5 on a frame's corners and face proposals: the boxes judged
// and kept, into det (its boxes, hypotheses, declined candidates and
// poses_ms).
absl::Status JudgeAndKeep(const PreparedFrame& frame, const SegmentGroups& groups,
                          const FaceProposals& faces, const std::optional<FloorPlane>& floor,
                          const CancelToken& cancel, Detection* det) {
  const DetectorOptions& options = frame.options;
  const Clock::time_point t0 = Clock::now();
  internal::HypothesisJudge judge(frame.depth, options, &cancel);
  // The floor (DetectorOptions::floor_check; FindFacesAndFloor) is known
  // before any box is judged: a reading with a corner more than
  // floor_tolerance_m through it (a pallet's deck board read as a box
  // reaches its own height into the floor, and so does a box of another
  // size read as this one on end) is declined when judged, so it cannot
  // outrank (and block) another reading of the same face. Every box kept is
  // judged so: no check after.
  if (floor) judge.SetFloor(floor->normal, floor->centroid, options.floor_tolerance_m);
  BoxAcceptance acceptance(options, cancel, &judge, det);
  ProposeFromCorners(*det, groups, options, &judge);
  acceptance.AcceptAll();
  const std::vector<EdgePairFace> pairs =
      ProposeFromEdgePairs(det->segments, options.box, options.edge_pairs);
  std::vector<DeclinedCandidate> declined;
  if (options.face_proposals) {
    AcceptFaceTilesAndCheck(frame, faces, pairs, floor, &judge, &acceptance, det, &declined);
  } else if (!pairs.empty()) {
    ProposeEdgePairs(pairs, acceptance, &judge);
    acceptance.AcceptAll();
  }
  AlignToLayerPlanes(frame.depth, options.box, options.layer_plane, &det->boxes);
  AlignToLayerTurns(options.box, options.layer_turn, &det->boxes);
  if (floor) {
    RestOnFloor(floor->normal, floor->centroid, options.box, options.floor_rest, &det->boxes);
  }
  if (absl::Status s = cancel.Check("the judging of hypotheses"); !s.ok()) return s;
  if (options.score_in_view) {
    for (DetectedBox& box : det->boxes) {
      box.score *= internal::BoxViewShare(frame.depth.camera, box.camera_T_box, options.box);
    }
  }
  std::stable_sort(det->boxes.begin(), det->boxes.end(),
                   [](const DetectedBox& a, const DetectedBox& b) { return a.score > b.score; });
  det->hypotheses = judge.stats();
  declined.insert(declined.end(), judge.declined().begin(), judge.declined().end());
  det->declined = StrongestDeclined(std::move(declined), det->boxes, options);
  det->timings.poses_ms += MsSince(t0);
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<Detection> DetectBoxes(const PointCloud& input, const DetectorOptions& options_in,
                                      const CancelToken& cancel) {
  const Clock::time_point t_start = Clock::now();
  PreparedFrame frame;
  if (absl::Status s = PrepareFrame(input, options_in, &frame); !s.ok()) return s;
  Detection det;
  if (frame.too_few_points) {
    det.timings.total_ms = MsSince(t_start);
    return det;
  }
  const DetectorOptions& options = frame.options;
  det.timings.preprocess_ms = MsSince(t_start);
  if (absl::Status s = cancel.Check("preprocessing"); !s.ok()) return s;

  SegmentGroups groups;
  FaceProposals faces;
  std::optional<FloorPlane> floor;
  if (absl::Status s = FindEdgesAndFaces(frame, cancel, &det, &groups, &faces, &floor); !s.ok()) {
    return s;
  }
  if (absl::Status s = JudgeAndKeep(frame, groups, faces, floor, cancel, &det); !s.ok()) return s;

  // Nothing found: the planar patches once more with a wider normal window
  // (DetectorOptions::empty_frame_window_cells), unless the caller chose
  // the window; the edge points, segments and corners stand as they are.
  const DetectorOptions defaults;
  if (det.boxes.empty() && options.empty_frame_window_cells > 0 && options.face_proposals &&
      options_in.faces.patches.window_cells == defaults.faces.patches.window_cells &&
      !det.edge_points.empty()) {
    FaceProposalOptions wider = options.faces;
    wider.patches.window_cells = options.empty_frame_window_cells;
    const Clock::time_point t_faces = Clock::now();
    std::optional<FloorPlane> wider_floor;
    const FaceProposals wider_faces =
        FindFacesAndFloor(frame.depth, options, wider, &cancel, nullptr, &wider_floor);
    det.timings.faces_ms += MsSince(t_faces);
    if (absl::Status s = cancel.Check("the planar patches"); !s.ok()) return s;
    if (absl::Status s = JudgeAndKeep(frame, groups, wider_faces, wider_floor, cancel, &det);
        !s.ok()) {
      return s;
    }
  }
  det.timings.total_ms = MsSince(t_start);
  return det;
}

}  // namespace cornerpose
