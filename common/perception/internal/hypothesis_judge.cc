#include "common/perception/internal/hypothesis_judge.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>

#include "absl/strings/str_format.h"
#include "common/perception/box_pose.h"
#include "common/perception/internal/border_faces.h"
#include "common/perception/internal/box_overlap.h"
#include "common/perception/internal/kept_neighbours.h"
#include "common/perception/internal/parallel.h"
#include "common/perception/pose_error.h"

namespace cornerpose::internal {
namespace {

constexpr char kMovedTooFar[] = "refinement moved it too far: not this box";
constexpr char kRunsOnFlat[] =
    "a side runs on flat with no seam (a bigger face, or a layer that does not tile uniquely)";
constexpr char kNotBoxedIn[] = "no free side and not boxed in by seams on all four";
constexpr char kLongerSide[] = "a hidden side could be a longer side of the box";

}  // namespace

bool TiltOntoDepth(const DepthImage& depth, const BoxDims& dims, Eigen::Isometry3d* pose) {
  const Eigen::Matrix3d R = pose->linear();
  const Eigen::Vector3d t = pose->translation();
  // The face most facing the camera.
  int best_axis = 0;
  double best_sign = 1.0, best_facing = -2.0;
  for (int i = 0; i < 3; ++i) {
    for (const double sgn : {1.0, -1.0}) {
      const Eigen::Vector3d n = sgn * R.col(i);
      const Eigen::Vector3d c = t + n * dims[i] / 2.0;
      const double facing = -c.normalized().dot(n);
      if (facing > best_facing) best_facing = facing, best_axis = i, best_sign = sgn;
    }
  }
  if (best_facing <= 0.2) return false;
  const int ia = (best_axis + 1) % 3, ib = (best_axis + 2) % 3;
  const Eigen::Vector3d n0 = best_sign * R.col(best_axis);
  const Eigen::Vector3d c0 = t + n0 * dims[best_axis] / 2.0;
  // A face a few dozen pixels across fits the noise, not its plane.
  if (c0.z() <= 0.05 ||
      std::min(dims[ia], dims[ib]) * depth.camera.fx / c0.z() < kTiltOntoDepthMinFacePx) {
    return false;
  }
  std::vector<Eigen::Vector3d> pts;
  const CameraIntrinsics& k = depth.camera;
  for (int i = 0; i < 9; ++i) {
    for (int j = 0; j < 9; ++j) {
      const Eigen::Vector3d q = c0 + (0.8 * (i / 8.0 - 0.5)) * dims[ia] * R.col(ia) +
                                (0.8 * (j / 8.0 - 0.5)) * dims[ib] * R.col(ib);
      if (q.z() <= 0.05) return false;
      const Eigen::Vector2d px = Project(k, q);
      const int u = static_cast<int>(std::lround(px.x())),
                v = static_cast<int>(std::lround(px.y()));
      if (!depth.inside(u, v)) continue;
      const float z = depth.at(u, v);
      if (std::isnan(z)) continue;
      pts.push_back(static_cast<double>(z) * PixelRay(k, u, v));
    }
  }
  Eigen::Vector3d n = n0, c = c0;
  for (const double tol : {0.04, 0.01}) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    int m = 0;
    for (const Eigen::Vector3d& p : pts) {
      if (std::abs((p - c).dot(n)) <= tol) mean += p, ++m;
    }
    if (m < 30) return false;
    mean /= m;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& p : pts) {
      if (std::abs((p - c).dot(n)) <= tol) cov += (p - mean) * (p - mean).transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Eigen::Vector3d fit = eig.eigenvectors().col(0);
    if (fit.dot(n0) < 0.0) fit = -fit;
    n = fit;
    c = mean;
  }
  const double angle = std::acos(std::clamp(n.dot(n0), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  if (angle < 2.0 || angle > 30.0) return false;
  const Eigen::Matrix3d turn = Eigen::Quaterniond::FromTwoVectors(n0, n).toRotationMatrix();
  pose->linear() = turn * R;
  pose->translation() = c0 + turn * (t - c0);
  return true;
}

std::string RefinementVerdict(const RefinementResult& ref, const BoxDims& dims, BoxFace grasp,
                              const AcceptanceOptions& o, int out_of_view_side,
                              unsigned longer_ruled_out) {
  // The in-plane position must be measured, not guessed: a free side along
  // each of the face's axes.
  const int fi = static_cast<int>(grasp);
  const int axis_a = (fi / 2 + 1) % 3, axis_b = (fi / 2 + 2) % 3;
  for (const auto& [extent, axis] :
       {std::pair{ref.extent_a_m, axis_a}, std::pair{ref.extent_b_m, axis_b}}) {
    if (extent > 0.0 && std::abs(extent - dims[axis]) > o.extent_tolerance_m) {
      return absl::StrFormat("face measures %.3f m where the box is %.3f m", extent, dims[axis]);
    }
  }
  if (o.max_short_both_axes_m > 0.0 && ref.extent_a_m > 0.0 && ref.extent_b_m > 0.0 &&
      dims[axis_a] - ref.extent_a_m > o.max_short_both_axes_m &&
      dims[axis_b] - ref.extent_b_m > o.max_short_both_axes_m) {
    return absl::StrFormat(
        "face measures %.3f x %.3f m, short of the box's %.3f x %.3f m both ways: a smaller box?",
        ref.extent_a_m, ref.extent_b_m, dims[axis_a], dims[axis_b]);
  }
  // Every side that can be seen must end the face: a free border or a seam
  // to a touching box. A face that runs on flat is a bigger face.
  int measured = 0;
  for (SideKind k : ref.sides) {
    if (k == SideKind::kContinues) {
      return kRunsOnFlat;
    }
    measured += k == SideKind::kFree || k == SideKind::kSeam || k == SideKind::kTiled;
  }
  // A side the face does not reach (seen through just inside it:
  // RefinementOptions::seen_through_share): the face there is smaller.
  for (int s = 0; s < 4; ++s) {
    if (ref.sides[s] == SideKind::kUnknown && ref.seen_through[s] && s != out_of_view_side) {
      return "the face is seen through just inside a side: it ends before it (a smaller face?)";
    }
  }
  // A side out of view that what is in view pins (SideOutOfViewPinned)
  // counts as measured: the box's size says where the face ends there.
  measured += out_of_view_side >= 0;
  // At least two sides pin the face down; a face with no free side must be
  // boxed in on all four (by seams or whole tiles of its layer).
  if (measured < 2) return "fewer than two sides of the face measured";
  if (ref.free_sides < 1 && measured < 4) {
    return kNotBoxedIn;
  }
  // A side hidden under something may hide more face: keep the box only if
  // no bigger side of the box could stand in for this one there (the
  // box's third side, or, with a side across it hidden too, the face
  // turned a quarter). A side with nothing seen near it (a shadow's missing
  // returns) may hide the box's third side as well.
  for (int s = 0; s < 4; ++s) {
    if (s == out_of_view_side) continue;
    const bool occluded = ref.sides[s] == SideKind::kOccluded;
    const bool unseen = o.check_unseen_sides && ref.sides[s] == SideKind::kUnknown;
    if (!occluded && !unseen) continue;
    const int here = s < 2 ? axis_a : axis_b, other = s < 2 ? axis_b : axis_a;
    // The side across hidden too: the face turned a quarter, unless the
    // turned check judges that reading at the corner of the two sides
    // opposite (both measured).
    const int across = s < 2 ? 2 : 0;
    auto ends = [&](int i) {
      return ref.sides[i] == SideKind::kFree || ref.sides[i] == SideKind::kSeam;
    };
    const bool turned_in_doubt =
        ref.sides[across] == SideKind::kOccluded &&
        !(o.turned_hidden_corner_to_check && ends(s ^ 1) && ends(across ^ 1));
    for (int k = 0; k < 3; ++k) {
      if ((k != here && k != other && dims[k] > dims[here] + o.extent_tolerance_m &&
           (longer_ruled_out & (1u << s)) == 0) ||
          (occluded && k == other && dims[k] > dims[here] + o.extent_tolerance_m &&
           turned_in_doubt)) {
        return kLongerSide;
      }
    }
  }
  return "";
}

double JudgeRefined(const BoxEvidence& ev, const RefinementResult& ref, const BoxDims& dims,
                    BoxFace grasp, const AcceptanceOptions& o, std::string* reason,
                    int out_of_view_side, unsigned longer_ruled_out) {
  auto reject = [&](std::string why) {
    if (reason != nullptr) *reason = std::move(why);
    return -1.0;
  };
  if (!ev.in_front_of_camera) return reject("not in front of the camera");
  if (!ref.ok) return reject(kMovedTooFar);
  const FaceEvidence& g = ev.faces[static_cast<int>(grasp)];
  if (g.expected < o.min_grasp_pixels) return reject("grasp face too small in the image");
  const double grasp_occluded = static_cast<double>(g.occluded) / g.expected;
  const double grasp_support = g.visible() > 0 ? static_cast<double>(g.agree) / g.visible() : 0.0;
  if (grasp_occluded > o.max_grasp_occluded) {
    return reject(
        absl::StrFormat("grasp face %.0f%% hidden by something in front", 100 * grasp_occluded));
  }
  if (grasp_support < o.min_grasp_support) {
    return reject(
        absl::StrFormat("grasp face only %.0f%% confirmed by the depth", 100 * grasp_support));
  }
  if (ev.support() < o.min_support) {
    return reject(absl::StrFormat("box only %.0f%% confirmed by the depth", 100 * ev.support()));
  }
  if (ev.see_through_fraction() > o.max_see_through) {
    return reject(absl::StrFormat("%.0f%% of the box seen through (free space where it would be)",
                                  100 * ev.see_through_fraction()));
  }
  // A box mostly hidden behind what is in front of it is more often a box
  // pushed through a surface (the floor, a neighbour) than a real one.
  if (ev.total.expected > 0 &&
      static_cast<double>(ev.total.occluded) / ev.total.expected > o.max_occluded) {
    return reject(absl::StrFormat("%.0f%% of the box hidden: sunk into a surface?",
                                  100.0 * ev.total.occluded / ev.total.expected));
  }
  if (std::string why = RefinementVerdict(ref, dims, grasp, o, out_of_view_side, longer_ruled_out);
      !why.empty()) {
    return reject(std::move(why));
  }
  return std::clamp(0.5 * grasp_support + 0.5 * ev.support() - 2.0 * ev.see_through_fraction() -
                        0.25 * grasp_occluded,
                    0.0, 1.0);
}

CornerHeights CornerHeightsAbove(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims,
                                 const Eigen::Vector3d& normal, const Eigen::Vector3d& on_plane) {
  CornerHeights out{std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()};
  for (const Eigen::Vector3d& corner : BoxCorners(camera_T_box, dims)) {
    const double h = normal.dot(corner - on_plane);
    out.lowest = std::min(out.lowest, h);
    out.highest = std::max(out.highest, h);
  }
  return out;
}

std::string ThroughFloor(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims,
                         const Eigen::Vector3d& normal, const Eigen::Vector3d& on_plane,
                         double tolerance_m) {
  const double deepest = -CornerHeightsAbove(camera_T_box, dims, normal, on_plane).lowest;
  if (deepest <= tolerance_m) return "";
  return absl::StrFormat(
      "the box would reach %.0f mm into the floor (a flat piece of something else of a face's "
      "size)",
      1000.0 * deepest);
}

bool OneSideOnFlat(const RefinementResult& ref) {
  int on_flat = 0;
  for (SideKind k : ref.sides) {
    if (k == SideKind::kContinues) {
      ++on_flat;
    } else if (k != SideKind::kFree && k != SideKind::kSeam && k != SideKind::kTiled) {
      return false;
    }
  }
  return on_flat == 1;
}

namespace {

// Every side of the grasp face measured where the face ends (free or a
// seam), with a free side on `free_axes` of its two axes (a free side is
// surer than a seam): the face is pinned down though a corner of it lies out
// of view.
bool PinnedOnEverySide(const std::array<SideKind, 4>& sides, int free_axes) {
  auto ends = [](SideKind k) { return k == SideKind::kFree || k == SideKind::kSeam; };
  const int axes = (sides[0] == SideKind::kFree || sides[1] == SideKind::kFree) +
                   (sides[2] == SideKind::kFree || sides[3] == SideKind::kFree);
  return std::all_of(sides.begin(), sides.end(), ends) && axes >= free_axes;
}

}  // namespace

HypothesisJudge::HypothesisJudge(const DepthImage& depth, const DetectorOptions& options,
                                 const CancelToken* cancel)
    : depth_(depth),
      options_(options),
      neighbour_refinement_(options.refinement),
      symmetries_(BoxSymmetries(options.box)),
      cancel_(cancel) {
  neighbour_refinement_.end_on_flat_shift_m = 0.0;
}

void HypothesisJudge::Propose(const Eigen::Isometry3d& camera_T_box, int corners,
                              std::vector<int> segments, bool from_face) {
  if (Seen(camera_T_box)) return;
  // A pose like one refined and declined before gets one more start: the
  // refinement's reading of a side can depend on where it starts (a side
  // read as hidden from one start is free from another), so a later
  // proposal (a face tile after a corner, a neighbour) is judged once more.
  bool retry = false;
  if (const int i = FindLike(second_chance_, camera_T_box); i >= 0) {
    second_chance_.erase(second_chance_.begin() + i);
    retry = true;
  }
  seen_.push_back(camera_T_box);
  ++stats_.proposed;
  queue_.push_back({camera_T_box, corners, std::move(segments), from_face, retry});
}

HypothesisJudge::Proposal* HypothesisJudge::ProposeBare(const Eigen::Isometry3d& camera_T_box) {
  const size_t queued = queue_.size();
  Propose(camera_T_box, 0, {});
  return queue_.size() > queued ? &queue_.back() : nullptr;
}

void HypothesisJudge::ProposeNeighbour(const Eigen::Isometry3d& camera_T_box, bool chained) {
  if (Proposal* p = ProposeBare(camera_T_box)) {
    p->neighbour = true;
    p->chained = chained;
  }
}

void HypothesisJudge::ProposePastDeclined(const Eigen::Isometry3d& camera_T_box, int steps) {
  if (Proposal* p = ProposeBare(camera_T_box)) p->past_declined = steps;
}

std::vector<Candidate> HypothesisJudge::Evaluate(int threads,
                                                 const std::vector<DetectedBox>& kept) {
  const int n = static_cast<int>(queue_.size());
  std::vector<Candidate> results(n);
  std::vector<char> accepted(n, 0), refined(n, 0), settled(n, 0);
  std::vector<std::string> reasons(n);
  if (const double m = options_.acceptance.settled_overlap_margin_m; m > 0.0) {
    for (int i = 0; i < n; ++i) {
      settled[i] = std::any_of(kept.begin(), kept.end(), [&](const DetectedBox& k) {
        return BoxesOverlap(k.camera_T_box, queue_[i].camera_T_box, options_.box, m);
      });
    }
  }
  // A hypothesis inside a box accepted before it in the batch (in the
  // order proposed) with all four sides free is settled too
  // (AcceptanceOptions::settle_within_batch): a box's corners, tiles and
  // neighbours propose it, and other readings of its place, several times
  // over. Threads take the next hypothesis when done with one (work
  // is uneven: most fail the first check); one whose predecessors are not
  // all judged yet is judged anyway unless a judged one already settles it,
  // and its verdict is dropped if a predecessor settles it after all. The
  // verdicts are those of judging one by one, whatever the threads' timing.
  const double m = options_.acceptance.settled_overlap_margin_m;
  const bool within = options_.acceptance.settle_within_batch && m > 0.0;
  // Hypothesis k lies inside one accepted among the first `upto` whose
  // face ends in a free border on all four sides: nothing judged after it
  // there could rank above it (AcceptAll keeps the most free sides first),
  // but for a higher score with as many.
  auto inside_accepted = [&](int k, int upto) {
    for (int j = 0; within && j < std::min(k, upto); ++j) {
      if (accepted[j] && results[j].refinement.free_sides >= 4 &&
          BoxesOverlap(results[j].box.camera_T_box, queue_[k].camera_T_box, options_.box, m)) {
        return true;
      }
    }
    return false;
  };
  std::vector<char> done(n, 0);
  std::mutex mu;
  int final_prefix = 0;  // [0, final_prefix): judged, verdicts final
  ParallelForChunks(n, 1, threads, [&](int, int i, int) {
    // Polled once a hypothesis, judged or not (the polls a cancellation
    // counts do not depend on the threads' timing).
    const bool stop = StopRequested(cancel_);
    bool judge = false;
    {
      std::lock_guard<std::mutex> lock(mu);
      if (!settled[i] && inside_accepted(i, final_prefix)) settled[i] = 1;
      judge = !settled[i];
    }
    if (judge && !stop) {
      bool r = false;
      const bool ok = EvaluateOne(queue_[i], kept, &results[i], &r, &reasons[i]);
      std::lock_guard<std::mutex> lock(mu);
      accepted[i] = ok;
      refined[i] = r;
    }
    std::lock_guard<std::mutex> lock(mu);
    done[i] = 1;
    for (; final_prefix < n && done[final_prefix]; ++final_prefix) {
      const int f = final_prefix;
      if (!settled[f] && inside_accepted(f, f)) {  // judged before that was known
        settled[f] = 1;
        accepted[f] = 0;
        refined[f] = 0;
      }
    }
  });
  std::vector<Candidate> out;
  std::vector<Eigen::Isometry3d> turned;  // DetectorOptions::turned_proposals
  for (int i = 0; i < n; ++i) {
    if (settled[i]) {
      // Not judged: as if never proposed (a second start kept for later).
      --stats_.proposed;
      if (const int s = FindLike(seen_, queue_[i].camera_T_box); s >= 0) {
        seen_.erase(seen_.begin() + s);
      }
      if (queue_[i].retry) second_chance_.push_back(queue_[i].camera_T_box);
      continue;
    }
    stats_.refined += refined[i];
    // Not a turned reading's own: turning it back is where it came from.
    if (!accepted[i] && refined[i] && reasons[i] == kRunsOnFlat && options_.turned_proposals &&
        !queue_[i].turned) {
      TurnedReadings(results[i], &turned);
    }
    if (!accepted[i]) {
      // A stepping stone: a neighbour (of a box accepted, or within the
      // allowed steps past declined ones) declined for a side on flat, or
      // for seams on only some of its sides and no free one (a side hidden
      // under the layer above), with a seam on another side (it lies in a
      // layer of touching boxes; a face running on flat everywhere else is
      // a bigger face or the floor, and stepping on from it only costs
      // time).
      const Proposal& q = queue_[i];
      const std::array<SideKind, 4>& sides = results[i].refinement.sides;
      const bool seamed = std::any_of(sides.begin(), sides.end(), [](SideKind k) {
        return k == SideKind::kSeam || k == SideKind::kTiled;
      });
      if (refined[i] && (reasons[i] == kRunsOnFlat || reasons[i] == kNotBoxedIn) && seamed &&
          (q.neighbour || q.past_declined > 0) &&
          q.past_declined < options_.neighbour_steps_past_declined) {
        stepping_stones_.push_back({results[i].box, q.past_declined + 1});
      }
      if (refined[i] && reasons[i] == kRunsOnFlat && options_.acceptance.pairs_end_each_other &&
          OneSideOnFlat(results[i].refinement)) {
        one_side_on_flat_.push_back(results[i]);
      }
      if (refined[i]) {
        declined_.push_back(
            {results[i].box.camera_T_box, results[i].box.score, std::move(reasons[i])});
        if (options_.retry_declined) {
          // Its proposed pose may be proposed once more (Propose).
          if (const int s = FindLike(seen_, queue_[i].camera_T_box); s >= 0 && !queue_[i].retry) {
            seen_.erase(seen_.begin() + s);
            second_chance_.push_back(queue_[i].camera_T_box);
          }
        }
      }
      continue;
    }
    ++stats_.accepted;
    out.push_back(std::move(results[i]));
  }
  queue_.clear();
  // Judged in the next round, as the neighbours of the boxes accepted here.
  for (const Eigen::Isometry3d& t : turned) {
    if (Proposal* p = ProposeBare(t)) p->turned = true;
  }
  return out;
}

void HypothesisJudge::TurnedReadings(const Candidate& declined,
                                     std::vector<Eigen::Isometry3d>* out) const {
  const int axis_n = static_cast<int>(declined.box.grasp_face) / 2;
  const double shorter = std::min(options_.box[(axis_n + 1) % 3], options_.box[(axis_n + 2) % 3]);
  if (shorter < options_.refinement.seam_turn_min_length_m) return;
  for (const Eigen::Isometry3d& t :
       TurnedAtMeasuredCorners(declined.box.camera_T_box, declined.box.grasp_face,
                               declined.refinement.sides, options_.box)) {
    out->push_back(t);
  }
}

Eigen::Isometry3d TurnedAtCorner(const Eigen::Isometry3d& camera_T_box, BoxFace grasp,
                                 const BoxDims& dims, double sa, double sb) {
  const int axis_n = static_cast<int>(grasp) / 2;
  const int axis_a = (axis_n + 1) % 3, axis_b = (axis_n + 2) % 3;
  const double A = dims[axis_a], B = dims[axis_b];
  const Eigen::Matrix3d R = camera_T_box.linear();
  Eigen::Isometry3d turned = camera_T_box;
  turned.linear() =
      R * Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::Unit(axis_n)).toRotationMatrix();
  // B along a, A along b, one corner in common.
  turned.translation() += 0.5 * (A - B) * (sa * R.col(axis_a) - sb * R.col(axis_b));
  return turned;
}

Eigen::Isometry3d LongerUnderSide(const Eigen::Isometry3d& camera_T_box, BoxFace grasp,
                                  const BoxDims& dims, int side) {
  const int axis_n = static_cast<int>(grasp) / 2;
  const double sign_n = static_cast<int>(grasp) % 2 == 0 ? 1.0 : -1.0;
  const int here = side < 2 ? (axis_n + 1) % 3 : (axis_n + 2) % 3;
  const int other = 3 - axis_n - here;
  const double sign_side = side % 2 == 0 ? 1.0 : -1.0;
  const double grow = 0.5 * (dims[axis_n] - dims[here]);
  // In the box's frame: the face runs dims[axis_n] from its opposite side,
  // the box dims[here] deep behind the face.
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  shift[here] = sign_side * grow;
  shift[axis_n] = sign_n * grow;
  Eigen::Isometry3d longer = camera_T_box;
  longer.translation() += camera_T_box.linear() * shift;
  longer.linear() =
      camera_T_box.linear() *
      Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::Unit(other)).toRotationMatrix();
  return longer;
}

unsigned LongerReadingsRuledOut(const DepthImage& depth, const Eigen::Isometry3d& pose,
                                BoxFace grasp, const RefinementResult& ref,
                                const DetectorOptions& options) {
  const double share = options.acceptance.unseen_longer_see_through;
  const int axis_n = static_cast<int>(grasp) / 2;
  const BoxDims& dims = options.box;
  unsigned out = 0;
  for (int s = 0; s < 4 && share > 0.0; ++s) {
    // Only where the box's third side is longer (RefinementVerdict's test).
    const int here = s < 2 ? (axis_n + 1) % 3 : (axis_n + 2) % 3;
    if (ref.sides[s] != SideKind::kUnknown ||
        dims[axis_n] <= dims[here] + options.acceptance.extent_tolerance_m) {
      continue;
    }
    const BoxEvidence ev = MeasureBox(depth, LongerUnderSide(pose, grasp, options.box, s),
                                      options.box, options.evidence);
    if (ev.see_through_fraction() >= share) out |= 1u << s;
  }
  return out;
}

std::vector<Eigen::Isometry3d> TurnedAtMeasuredCorners(const Eigen::Isometry3d& camera_T_box,
                                                       BoxFace grasp,
                                                       const std::array<SideKind, 4>& sides,
                                                       const BoxDims& dims) {
  std::vector<Eigen::Isometry3d> out;
  const int axis_n = static_cast<int>(grasp) / 2;
  if (std::abs(dims[(axis_n + 1) % 3] - dims[(axis_n + 2) % 3]) < 0.02) return out;
  auto measured = [](SideKind k) { return k == SideKind::kFree || k == SideKind::kSeam; };
  for (double sa : {1.0, -1.0}) {
    for (double sb : {1.0, -1.0}) {
      if (measured(sides[sa > 0 ? 0 : 1]) && measured(sides[sb > 0 ? 2 : 3])) {
        out.push_back(TurnedAtCorner(camera_T_box, grasp, dims, sa, sb));
      }
    }
  }
  return out;
}

std::optional<Candidate> HypothesisJudge::JudgeAlone(const Eigen::Isometry3d& camera_T_box,
                                                     const std::vector<DetectedBox>& kept,
                                                     std::string* reason) const {
  Candidate c;
  bool refined = false;
  std::string why;
  const bool ok = EvaluateOne(Proposal{camera_T_box, 0, {}, false}, kept, &c, &refined, &why);
  if (reason != nullptr) *reason = ok ? "" : std::move(why);
  if (!ok) return std::nullopt;
  return c;
}

bool HypothesisJudge::EvaluateOne(const Proposal& p, const std::vector<DetectedBox>& kept,
                                  Candidate* out, bool* refined, std::string* reason) const {
  if (EvaluateFrom(p, p.camera_T_box, kept, out, refined, reason)) return true;
  // A corner's reading the gate turned away or the refinement moved too
  // far gets a second start with its face on the depth's plane
  // (DetectorOptions::corner_tilt_onto_depth).
  if (p.corners <= 0 || p.neighbour || !options_.corner_tilt_onto_depth ||
      (*refined && *reason != kMovedTooFar)) {
    return false;
  }
  Eigen::Isometry3d tilted = p.camera_T_box;
  if (!TiltOntoDepth(depth_, options_.box, &tilted)) return false;
  Candidate second;
  bool refined_second = false;
  std::string why;
  const bool ok = EvaluateFrom(p, tilted, kept, &second, &refined_second, &why);
  if (ok || (refined_second && !*refined)) {
    *out = std::move(second);
    *refined = refined_second;
    *reason = std::move(why);
  }
  return ok;
}

bool HypothesisJudge::EvaluateFrom(const Proposal& p, const Eigen::Isometry3d& start,
                                   const std::vector<DetectedBox>& kept, Candidate* out,
                                   bool* refined, std::string* reason) const {
  Candidate& cand = *out;
  cand.box.camera_T_box = start;
  cand.box.num_corners = p.corners;
  cand.box.segments = p.segments;
  cand.box.from_face = p.from_face;
  if (floor_ && BeyondRefinementOutOfFloor(start)) return false;
  EvidenceOptions gate = options_.evidence;
  gate.max_samples = std::min(gate.max_samples, gate.gate_max_samples);
  const BoxEvidence first = MeasureBox(depth_, cand.box.camera_T_box, options_.box, gate);
  // Refinement moves a hypothesis by centimetres at most: one that the
  // depth image already rejects by a wide margin is not worth refining.
  const BoxFace grasp = first.grasp_face;
  const FaceEvidence& g = first.faces[static_cast<int>(grasp)];
  if (!first.in_front_of_camera || first.see_through_fraction() > 0.2 || first.support() < 0.4 ||
      g.visible() <= 0 || static_cast<double>(g.agree) / g.visible() < 0.5) {
    return false;
  }
  // Unrefined corners can be a centimetre off: only the refined face must
  // lie inside the image (checked below). Where a face measured on every
  // side may leave the view, that check decides: here its centre and some
  // of each of its sides need only be in view (a neighbour of a box found,
  // out past the image's edge).
  const AcceptanceOptions& acceptance = options_.acceptance;
  if (!GraspFaceInView(cand.box.camera_T_box, grasp, -20.0) &&
      !(acceptance.measured_face_may_leave_view &&
        GraspFaceMeasurable(cand.box.camera_T_box, grasp,
                            acceptance.face_may_run_out_of_view ? 3 : 4))) {
    return false;
  }
  *refined = true;
  cand.box.score = first.support();  // what a declined candidate reports
  // A neighbour of a box found may be a stepping stone: its seam may show
  // only in the refinement's second iteration, so it gets every iteration.
  // One proposed past a declined neighbour ends on flat after one, as a
  // hypothesis from the frame does (on a brick pallet they were two thirds
  // of the refinements; the same boxes on every evaluation set).
  const bool may_end_on_flat =
      (!p.neighbour && !p.chained && p.past_declined == 0) || (p.past_declined > 0 && !p.chained);
  cand.refinement = RefineOnGraspFace(depth_, options_.box, grasp,
                                      may_end_on_flat ? options_.refinement : neighbour_refinement_,
                                      &cand.box.camera_T_box);
  cand.box.grasp_face = grasp;  // what a stepping stone proposes from
  // The pose did not move (the gate saw it in front of the camera): the
  // full evidence would only confirm what JudgeRefined rejects it for.
  if (!cand.refinement.ok) {
    *reason = kMovedTooFar;
    return false;
  }
  SeamsAgainstKept(cand.box.camera_T_box, grasp, kept, &cand.refinement);
  // A face the border cuts: is it pinned up to the border?
  // Or a corner of it just past the border, its sides all read.
  const bool in_view =
      GraspFaceInView(cand.box.camera_T_box, grasp, acceptance.border_margin_px) ||
      (acceptance.max_out_of_view_share > 0.0 &&
       std::none_of(cand.refinement.sides.begin(), cand.refinement.sides.end(),
                    [](SideKind k) { return k == SideKind::kUnknown; }) &&
       GraspFaceOutOfView(cand.box.camera_T_box, grasp, acceptance.border_margin_px) <=
           acceptance.max_out_of_view_share);
  const int out_of_view = OutOfViewSide(cand.box.camera_T_box, grasp, cand.refinement, in_view);
  // What the refinement alone rejects (most often a side that runs on flat:
  // two thirds of all refined hypotheses) needs no full evidence.
  unsigned longer_ruled_out = 0;
  if (std::string why =
          Verdict(cand.box.camera_T_box, grasp, cand.refinement, out_of_view, &longer_ruled_out);
      !why.empty()) {
    *reason = std::move(why);
    return false;
  }
  cand.evidence = MeasureBox(depth_, cand.box.camera_T_box, options_.box, options_.evidence);
  const double score = JudgeRefined(cand.evidence, cand.refinement, options_.box, grasp, acceptance,
                                    reason, out_of_view, longer_ruled_out);
  if (score < 0.0) return false;
  if (floor_) {
    if (std::string why = ThroughFloor(cand.box.camera_T_box, options_.box, floor_->normal,
                                       floor_->centroid, floor_->tolerance_m);
        !why.empty()) {
      *reason = std::move(why);
      return false;
    }
  }
  if (!in_view && out_of_view < 0 &&
      !(acceptance.measured_face_may_leave_view &&
        PinnedOnEverySide(cand.refinement.sides, acceptance.leaving_view_free_axes))) {
    *reason = "grasp face cut by the image border";
    return false;
  }
  // Proposed past a declined neighbour (DetectorOptions::
  // neighbour_steps_past_declined): refined again from its refined pose,
  // it must still pass.
  cand.chained = p.past_declined > 0 || p.chained;
  if (cand.chained) {
    Eigen::Isometry3d again = cand.box.camera_T_box;
    RefinementResult second =
        RefineOnGraspFace(depth_, options_.box, grasp, options_.refinement, &again);
    SeamsAgainstKept(again, grasp, kept, &second);
    const int again_out_of_view = OutOfViewSide(
        again, grasp, second, GraspFaceInView(again, grasp, acceptance.border_margin_px));
    unsigned again_ruled_out = 0;
    const std::string why = second.ok
                                ? Verdict(again, grasp, second, again_out_of_view, &again_ruled_out)
                                : std::string(kMovedTooFar);
    if (!why.empty()) {
      *reason = "refined once more from where it was refined, " + why;
      return false;
    }
  }
  cand.box.score = score;
  cand.box.measured_extent_m = {cand.refinement.extent_a_m, cand.refinement.extent_b_m};
  cand.box.grasp_face = cand.evidence.grasp_face;
  const Eigen::Vector3d n_box = BoxFaceNormal(cand.box.grasp_face);
  const int axis = static_cast<int>(cand.box.grasp_face) / 2;
  cand.box.grasp_normal_camera = cand.box.camera_T_box.linear() * n_box;
  cand.box.grasp_centre_camera = cand.box.camera_T_box * (n_box * options_.box[axis] / 2.0);
  // A face seen nearly edge-on has too few, too noisy points to confirm a
  // box by, and is where the sides of pallets and bins pass for one.
  const double cos_view =
      -cand.box.grasp_normal_camera.dot(cand.box.grasp_centre_camera.normalized());
  if (cos_view < std::cos(options_.acceptance.max_grasp_view_angle_deg * M_PI / 180.0)) {
    *reason = "grasp face seen too obliquely";
    return false;
  }
  return true;
}

std::string HypothesisJudge::Verdict(const Eigen::Isometry3d& pose, BoxFace grasp,
                                     const RefinementResult& ref, int out_of_view,
                                     unsigned* longer_ruled_out) const {
  *longer_ruled_out = 0;
  std::string why = RefinementVerdict(ref, options_.box, grasp, options_.acceptance, out_of_view);
  if (why != kLongerSide) return why;
  *longer_ruled_out = LongerReadingsRuledOut(depth_, pose, grasp, ref, options_);
  return RefinementVerdict(ref, options_.box, grasp, options_.acceptance, out_of_view,
                           *longer_ruled_out);
}

std::optional<Eigen::Vector2d> HypothesisJudge::GraspFacePixel(const Eigen::Isometry3d& pose,
                                                               BoxFace face, double sa,
                                                               double sb) const {
  const int f = static_cast<int>(face);
  const int n = f / 2, a = (n + 1) % 3, b = (n + 2) % 3;
  Eigen::Vector3d local = Eigen::Vector3d::Zero();
  local[n] = (f % 2 == 0 ? 0.5 : -0.5) * options_.box[n];
  local[a] = sa * options_.box[a];
  local[b] = sb * options_.box[b];
  const Eigen::Vector3d p = pose * local;
  if (p.z() <= 0.05) return std::nullopt;
  return Project(depth_.camera, p);
}

// A face cut by the image border cannot be checked to its end (and a
// gripper aimed at its centre may miss the box): such boxes are not
// returned, unless every side was found where the face ends
// (PinnedOnEverySide).
bool HypothesisJudge::GraspFaceInView(const Eigen::Isometry3d& pose, BoxFace face,
                                      double margin) const {
  const CameraIntrinsics& k = depth_.camera;
  for (double sa : {-0.5, 0.5}) {
    for (double sb : {-0.5, 0.5}) {
      const std::optional<Eigen::Vector2d> px = GraspFacePixel(pose, face, sa, sb);
      if (!px || px->x() < margin || px->y() < margin || px->x() > k.width - 1 - margin ||
          px->y() > k.height - 1 - margin) {
        return false;
      }
    }
  }
  return true;
}

double HypothesisJudge::GraspFaceOutOfView(const Eigen::Isometry3d& pose, BoxFace face,
                                           double margin) const {
  const CameraIntrinsics& k = depth_.camera;
  constexpr int kSteps = 10;
  int out = 0;
  for (int i = 0; i < kSteps; ++i) {
    for (int j = 0; j < kSteps; ++j) {
      const std::optional<Eigen::Vector2d> px =
          GraspFacePixel(pose, face, (i + 0.5) / kSteps - 0.5, (j + 0.5) / kSteps - 0.5);
      out += !px || px->x() < margin || px->y() < margin || px->x() > k.width - 1 - margin ||
             px->y() > k.height - 1 - margin;
    }
  }
  return static_cast<double>(out) / (kSteps * kSteps);
}

void HypothesisJudge::SeamsAgainstKept(const Eigen::Isometry3d& pose, BoxFace grasp,
                                       const std::vector<DetectedBox>& kept,
                                       RefinementResult* ref) const {
  if (!options_.acceptance.kept_box_ends_side || kept.empty() || !ref->ok) return;
  for (int s = 0; s < 4; ++s) {
    if (ref->sides[s] == SideKind::kContinues &&
        SideAgainstKeptBox(pose, grasp, options_.box, s, kept)) {
      ref->sides[s] = SideKind::kSeam;
    }
  }
}

int HypothesisJudge::OutOfViewSide(const Eigen::Isometry3d& pose, BoxFace grasp,
                                   const RefinementResult& ref, bool in_view) const {
  if (in_view || !ref.ok || !options_.acceptance.face_may_run_out_of_view) return -1;
  return SideOutOfViewPinned(depth_, pose, grasp, options_.box, ref, options_.acceptance,
                             options_.refinement.plane_tolerance_m);
}

bool HypothesisJudge::GraspFaceMeasurable(const Eigen::Isometry3d& pose, BoxFace face,
                                          int sides_in_view) const {
  auto in_view = [&](double sa, double sb) {
    const std::optional<Eigen::Vector2d> px = GraspFacePixel(pose, face, sa, sb);
    return px && depth_.inside(static_cast<int>(std::floor(px->x())),
                               static_cast<int>(std::floor(px->y())));
  };
  if (!in_view(0.0, 0.0)) return false;
  // With a side out of view, the face's middle fifth on both axes in view:
  // whichever side the border cuts, 60 % of the face is in view
  // (AcceptanceOptions::min_in_view_share decides after refinement).
  if (sides_in_view < 4 &&
      !(in_view(0.1, 0.0) && in_view(-0.1, 0.0) && in_view(0.0, 0.1) && in_view(0.0, -0.1))) {
    return false;
  }
  // Every side needs some of its length in view to be measured, which a
  // face leaving the view must be on all four (PinnedOnEverySide).
  int sides = 0;
  for (const double s : {-0.5, 0.5}) {
    bool a_side = false, b_side = false;
    for (const double t : {-0.25, 0.0, 0.25}) {
      a_side = a_side || in_view(s, t);
      b_side = b_side || in_view(t, s);
    }
    sides += a_side + b_side;
  }
  return sides >= sides_in_view;
}

int HypothesisJudge::FindLike(const std::vector<Eigen::Isometry3d>& poses,
                              const Eigen::Isometry3d& pose) const {
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d& s = poses[i];
    if ((s.translation() - pose.translation()).norm() > 0.01) continue;
    for (const Eigen::Matrix3d& S : symmetries_) {
      if ((s.linear() - pose.linear() * S).norm() < 0.06) {  // ~2.5 degrees
        return static_cast<int>(i);
      }
    }
  }
  return -1;
}

bool HypothesisJudge::BeyondRefinementOutOfFloor(const Eigen::Isometry3d& pose) const {
  // A refinement within its limits moves the box's centre max_shift_m and
  // turns it max_turn_deg about it: a corner at most that shift plus the
  // chord of that turn on the box's half diagonal (and 5 mm to spare).
  const BoxDims& d = options_.box;
  const double half_diagonal = 0.5 * std::sqrt(d.l * d.l + d.b * d.b + d.h * d.h);
  const double reach =
      floor_->tolerance_m + options_.refinement.max_shift_m +
      2.0 * half_diagonal * std::sin(options_.refinement.max_turn_deg * std::numbers::pi / 360.0) +
      0.005;
  return -CornerHeightsAbove(pose, d, floor_->normal, floor_->centroid).lowest > reach;
}

bool HypothesisJudge::Seen(const Eigen::Isometry3d& pose) const {
  return FindLike(seen_, pose) >= 0;
}

}  // namespace cornerpose::internal
