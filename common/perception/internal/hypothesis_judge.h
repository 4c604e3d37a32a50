// Judging box pose hypotheses against the depth image: a cheap
// render-and-compare first, then refinement on the grasp face and the full
// acceptance test. Hypotheses are queued (duplicates dropped) and evaluated
// in parallel; each evaluation only reads the depth image.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/perception/box_evidence.h"
#include "common/perception/box_refinement.h"
#include "common/perception/camera_model.h"
#include "common/perception/cancel_token.h"
#include "common/perception/detector.h"
#include "common/perception/types.h"

namespace cornerpose::internal {

struct Candidate {
  DetectedBox box;
  BoxEvidence evidence;
  RefinementResult refinement;
  // Reached through a stepping stone (proposed by one, or by a box so
  // reached): its own neighbours are checked as strictly.
  bool chained = false;
};

// The part of the acceptance test the refinement alone decides (the face's
// measured extents and how its sides end): "" when it passes, else why not.
// `out_of_view_side`: a side of the face out of view that what is in view
// pins (SideOutOfViewPinned), counted as measured; -1: none.
// `longer_ruled_out`: bit s set when the depth image rules out that side s,
// unseen, hides the face running on to the box's third side
// (LongerUnderSide): that side then leaves the face's size in no doubt.
std::string RefinementVerdict(const RefinementResult& ref, const BoxDims& dims, BoxFace grasp,
                              const AcceptanceOptions& o, int out_of_view_side = -1,
                              unsigned longer_ruled_out = 0);

// True when exactly one side of the face runs on flat (kContinues) and the
// other three end it (free, a seam or tiled).
bool OneSideOnFlat(const RefinementResult& ref);

// The acceptance test of a refined hypothesis: its score in [0, 1], or < 0
// when the depth image contradicts it (see AcceptanceOptions); then
// `reason`, when given, says which test failed.
double JudgeRefined(const BoxEvidence& ev, const RefinementResult& ref, const BoxDims& dims,
                    BoxFace grasp, const AcceptanceOptions& o, std::string* reason = nullptr,
                    int out_of_view_side = -1, unsigned longer_ruled_out = 0);

// The box turned a quarter about its grasp face's normal, flush with the
// face's corner at (sa, sb) (each +1 or -1 along the face's a and b axes):
// the other way to read a face from one of its corners.
Eigen::Isometry3d TurnedAtCorner(const Eigen::Isometry3d& camera_T_box, BoxFace grasp,
                                 const BoxDims& dims, double sa, double sb);

// The box read on a bigger face than its grasp face: side `side` of the
// grasp face (as RefinementResult::sides) hidden, the face running on under
// it to the box's third side, the opposite side where it is and the box
// that side's length deep behind the face.
Eigen::Isometry3d LongerUnderSide(const Eigen::Isometry3d& camera_T_box, BoxFace grasp,
                                  const BoxDims& dims, int side);

// The unseen (kUnknown) sides of a refined face whose longer reading
// (LongerUnderSide) the depth image rules out: at least AcceptanceOptions::
// unseen_longer_see_through of it seen through (RefinementVerdict's
// `longer_ruled_out`). Bit s: side s.
unsigned LongerReadingsRuledOut(const DepthImage& depth, const Eigen::Isometry3d& pose,
                                BoxFace grasp, const RefinementResult& ref,
                                const DetectorOptions& options);

// The box turned a quarter at each corner of its grasp face between two
// measured sides (free or a seam; `sides` as RefinementResult::sides), in
// the order (+a, +b), (+a, -b), (-a, +b), (-a, -b); none for a face whose
// sides differ by less than 2 cm (turned, it is the same face).
std::vector<Eigen::Isometry3d> TurnedAtMeasuredCorners(const Eigen::Isometry3d& camera_T_box,
                                                       BoxFace grasp,
                                                       const std::array<SideKind, 4>& sides,
                                                       const BoxDims& dims);

// The lowest and the highest of a box's eight corners above a plane
// (`normal` towards the camera, `on_plane` a point of it), metres: below
// it where negative.
struct CornerHeights {
  double lowest, highest;
};
CornerHeights CornerHeightsAbove(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims,
                                 const Eigen::Vector3d& normal, const Eigen::Vector3d& on_plane);

// Why a box cannot be there when it reaches more than tolerance_m through
// a plane (the floor: `normal` towards the camera, `on_plane` a point of
// it), its deepest corner measured away from the camera; "" when it does
// not.
std::string ThroughFloor(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims,
                         const Eigen::Vector3d& normal, const Eigen::Vector3d& on_plane,
                         double tolerance_m);

// A corner hypothesis's face turned onto the depth image's plane there:
// the corner's two segments give the face's normal as their cross product,
// and on an active stereo camera a segment's depth is noisy enough to tilt
// a face by 15-20 degrees, more than refinement may turn it. The face most
// facing the camera is fitted to the depth of its middle (a 9 x 9 grid over
// its inner 80 %, within 4 cm of the face, then within 1 cm of that fit);
// when the fitted normal differs by 2-30 degrees the box turns about the
// face's centre onto it. Faces whose shorter side spans fewer than
// kTiltOntoDepthMinFacePx pixels are left (a brick top at 2 m on a stereo
// camera fits the noise, not its plane: boxes 11-15 degrees off). False
// when the pose did not turn (DetectorOptions::corner_tilt_onto_depth).
inline constexpr double kTiltOntoDepthMinFacePx = 40.0;
bool TiltOntoDepth(const DepthImage& depth, const BoxDims& dims, Eigen::Isometry3d* pose);

class HypothesisJudge {
 public:
  // A stopped `cancel` (may be null) leaves the rest of a queue unjudged.
  HypothesisJudge(const DepthImage& depth, const DetectorOptions& options,
                  const CancelToken* cancel = nullptr);

  // Queues a pose unless one like it (same place within 1 cm, same
  // orientation up to the box's symmetries) was proposed before: the
  // corners of one box propose it many times. One that was refined and
  // declined is queued once more (with retry_declined).
  void Propose(const Eigen::Isometry3d& camera_T_box, int corners, std::vector<int> segments,
               bool from_face = false);
  // Queues a neighbour of a box accepted: judged alike, and, declined only
  // for a side that runs on flat with a seam on another, a stepping stone
  // (TakeSteppingStones). `chained`: the box proposing it was reached
  // through a stepping stone (Candidate::chained), and this one, once
  // accepted, must pass again from its refined pose too.
  void ProposeNeighbour(const Eigen::Isometry3d& camera_T_box, bool chained = false);
  // Queues a neighbour of a stepping stone `steps` declined boxes past the
  // last box accepted: judged alike, and once accepted refined again from
  // its refined pose, where it must pass again; a stepping stone itself
  // while steps < DetectorOptions::neighbour_steps_past_declined.
  void ProposePastDeclined(const Eigen::Isometry3d& camera_T_box, int steps);

  // Evaluates the queue on up to `threads` threads; returns the accepted
  // candidates in the order they were proposed, and empties the queue.
  // Hypotheses that got as far as refinement and failed are kept, with the
  // reason, in declined(). Those that overlap a box of `kept` too deeply
  // for refinement to free them (AcceptanceOptions::
  // settled_overlap_margin_m) are not judged, and may be proposed again.
  std::vector<Candidate> Evaluate(int threads, const std::vector<DetectedBox>& kept = {});
  // Judges one pose now, outside the queue: no duplicate is dropped and
  // nothing is recorded. The accepted candidate, or nothing (then, with
  // `reason`, why; "" when it did not get as far as refinement). `kept`:
  // boxes taken as kept (a side against one is a seam: SeamsAgainstKept).
  std::optional<Candidate> JudgeAlone(const Eigen::Isometry3d& camera_T_box,
                                      const std::vector<DetectedBox>& kept = {},
                                      std::string* reason = nullptr) const;
  // The hypotheses refined and declined since the last call only for one
  // side that runs on flat, every other side ended (OneSideOnFlat;
  // AcceptanceOptions::pairs_end_each_other): two of them that run on flat
  // into each other may end each other.
  std::vector<Candidate> TakeOneSideOnFlat() { return std::exchange(one_side_on_flat_, {}); }

  // A neighbour declined only because a side of its face runs on flat,
  // with a seam on another side: what it would have proposed as
  // neighbours is still worth judging.
  struct SteppingStone {
    DetectedBox box;  // the refined pose, its grasp face set
    int steps = 1;    // declined boxes past the last accepted, itself included
  };
  // The stepping stones among the hypotheses evaluated since the last call
  // (DetectorOptions::neighbour_steps_past_declined).
  std::vector<SteppingStone> TakeSteppingStones() { return std::exchange(stepping_stones_, {}); }

  // A plane no box reaches through by more than tolerance_m (the floor,
  // DetectorOptions::floor_check): a hypothesis that does is declined when
  // judged, before it can outrank a reading of the same face that does not.
  void SetFloor(const Eigen::Vector3d& normal, const Eigen::Vector3d& centroid,
                double tolerance_m) {
    floor_ = Floor{normal, centroid, tolerance_m};
  }

  // Proposals queued and not yet evaluated (the turned readings of the last
  // round's declined hypotheses: DetectorOptions::turned_proposals).
  bool Queued() const { return !queue_.empty(); }
  const HypothesisStats& stats() const { return stats_; }
  const std::vector<DeclinedCandidate>& declined() const { return declined_; }

 private:
  struct Proposal {
    Eigen::Isometry3d camera_T_box;
    int corners;
    std::vector<int> segments;
    bool from_face;
    bool retry = false;      // a second start at a pose declined once
    bool turned = false;     // a declined hypothesis's turned reading
    bool neighbour = false;  // proposed by a box accepted
    bool chained = false;    // ... one reached through a stepping stone
    int past_declined = 0;   // proposed by a stepping stone this many declined boxes past
                             // the last accepted (0: not)
  };
  // Propose() with no corners or segments: the queued proposal, for the
  // caller to mark, or null when it was seen before.
  Proposal* ProposeBare(const Eigen::Isometry3d& camera_T_box);
  // The face of a hypothesis declined for a side on flat, turned a quarter
  // at each corner between two measured sides (TurnedAtCorner), appended to
  // `out` (DetectorOptions::turned_proposals).
  void TurnedReadings(const Candidate& declined, std::vector<Eigen::Isometry3d>* out) const;
  // Evaluates one proposal; false when rejected. `refined` is set when it
  // got as far as refinement; then `reason` says why it was rejected, and
  // out->box holds the refined pose and out->box.score its first support.
  // `kept`: the boxes kept so far (SeamsAgainstKept).
  bool EvaluateOne(const Proposal& p, const std::vector<DetectedBox>& kept, Candidate* out,
                   bool* refined, std::string* reason) const;
  // EvaluateOne's judgement of `p` started from `start` instead of its pose.
  bool EvaluateFrom(const Proposal& p, const Eigen::Isometry3d& start,
                    const std::vector<DetectedBox>& kept, Candidate* out, bool* refined,
                    std::string* reason) const;
  // RefinementVerdict of a refined face at `pose`; where that is a hidden
  // side a longer side could stand in, again with the longer readings the
  // depth rules out (LongerReadingsRuledOut, set in *longer_ruled_out for
  // JudgeRefined).
  std::string Verdict(const Eigen::Isometry3d& pose, BoxFace grasp, const RefinementResult& ref,
                      int out_of_view, unsigned* longer_ruled_out) const;
  // A side the refinement found running on flat that lies against a box of
  // `kept` (SideAgainstKeptBox) is a seam: the kept box vouches for it.
  void SeamsAgainstKept(const Eigen::Isometry3d& pose, BoxFace grasp,
                        const std::vector<DetectedBox>& kept, RefinementResult* ref) const;
  // The pixel of a point of the grasp face (sa, sb in [-0.5, 0.5] along its
  // two axes), or nothing behind the camera.
  std::optional<Eigen::Vector2d> GraspFacePixel(const Eigen::Isometry3d& pose, BoxFace face,
                                                double sa, double sb) const;
  bool GraspFaceInView(const Eigen::Isometry3d& pose, BoxFace face, double margin) const;
  // The share of the grasp face (a 10 x 10 grid of its points) that
  // projects outside the image shrunk by `margin` pixels, or behind the
  // camera.
  double GraspFaceOutOfView(const Eigen::Isometry3d& pose, BoxFace face, double margin) const;
  // The grasp face's centre in view, and on `sides_in_view` of its sides a
  // point (at a quarter, half or three quarters of it).
  bool GraspFaceMeasurable(const Eigen::Isometry3d& pose, BoxFace face, int sides_in_view) const;
  // The side of a refined face not `in_view` that what is in view pins
  // (SideOutOfViewPinned, with AcceptanceOptions::face_may_run_out_of_view),
  // or -1.
  int OutOfViewSide(const Eigen::Isometry3d& pose, BoxFace grasp, const RefinementResult& ref,
                    bool in_view) const;
  bool Seen(const Eigen::Isometry3d& pose) const;
  // With a floor set: `pose` reaches so far through it that no refinement
  // within RefinementOptions::max_shift_m and max_turn_deg brings it back
  // within the floor's tolerance. Such a hypothesis is not judged: it
  // could only be declined (before session 31 it was refined first: 40 %
  // of all refinements on detector_bench's clutter set).
  bool BeyondRefinementOutOfFloor(const Eigen::Isometry3d& pose) const;
  // The index in `poses` of one like `pose` (within 1 cm, axes within
  // ~2.5 degrees up to the box's symmetries), or -1.
  int FindLike(const std::vector<Eigen::Isometry3d>& poses, const Eigen::Isometry3d& pose) const;

  struct Floor {
    Eigen::Vector3d normal, centroid;  // the normal points at the camera
    double tolerance_m;
  };
  std::optional<Floor> floor_;
  const DepthImage& depth_;
  const DetectorOptions& options_;
  // options_.refinement for the neighbours of boxes found: every iteration.
  RefinementOptions neighbour_refinement_;
  const std::vector<Eigen::Matrix3d> symmetries_;
  const CancelToken* const cancel_;
  std::vector<Eigen::Isometry3d> seen_;
  // Proposed poses refined and declined once: one more proposal like one
  // of them is judged (DetectorOptions::retry_declined).
  std::vector<Eigen::Isometry3d> second_chance_;
  std::vector<Proposal> queue_;
  HypothesisStats stats_;
  std::vector<DeclinedCandidate> declined_;
  std::vector<SteppingStone> stepping_stones_;
  std::vector<Candidate> one_side_on_flat_;
};

}  // namespace cornerpose::internal
