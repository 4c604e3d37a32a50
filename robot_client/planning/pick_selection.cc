#include "robot_client/planning/pick_selection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"
#include "robot_client/planning/pick_plan.h"

namespace cornerpose::robot_client {
namespace {

std::string Xyz(const Eigen::Vector3d& p) {
  return absl::StrFormat("(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
}

// Empty when one of the four grasps has G, M and R inside the workspace and
// reachable; otherwise why the first (least wrist rotation) grasp fails.
std::string CheckPickWaypoints(const BoxInBase& box, const Workspace& workspace,
                               const WaypointOptions& waypoints, const Reachability& reachable) {
  const double approach = ApproachDistance(box, waypoints);
  const double retrieve = RetrieveHeight(box, waypoints);
  const std::array<Eigen::Isometry3d, 4> grasps =
      GraspCandidates(box, Eigen::Quaterniond::Identity());
  // Positions are the same for all four grasps: test the workspace once.
  const Eigen::Isometry3d& g = grasps[0];
  const std::array<std::pair<const char*, Eigen::Isometry3d>, 3> points = {{
      {"grasp point G", g},
      {"approach point M", RaisedAlongBaseZ(g, approach)},
      {"retrieve point R", RaisedAlongBaseZ(g, retrieve)},
  }};
  for (const auto& [name, pose] : points) {
    if (!workspace.Contains(pose.translation())) {
      return absl::StrFormat("%s %s is outside the workspace", name, Xyz(pose.translation()));
    }
  }
  if (!reachable) return "";
  for (const Eigen::Isometry3d& grasp : grasps) {
    bool all = true;
    for (double height : {0.0, approach, retrieve}) {
      if (!reachable(RaisedAlongBaseZ(grasp, height))) {
        all = false;
        break;
      }
    }
    if (all) return "";
  }
  return absl::StrFormat("grasp at %s is not reachable (G, M or R, every tool rotation)",
                         Xyz(g.translation()));
}

// A detected box as the pile sees it: its highest point and its footprint,
// the rectangle it covers in base x, y (centre, unit axes, half sides).
struct Footprint {
  double top_z = 0.0;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  std::array<Eigen::Vector2d, 2> axis;
  std::array<double, 2> half{};
};

Footprint FootprintOf(const BoxInBase& box, const BoxDims& dims) {
  const Eigen::Matrix3d& R = box.base_T_box.linear();
  Footprint f;
  f.top_z = box.base_T_box.translation().z();
  for (int k = 0; k < 3; ++k) f.top_z += 0.5 * dims[k] * std::abs(R(2, k));
  // The box axis nearest base z is the footprint's normal; the other two span it.
  int up = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(R(2, k)) > std::abs(R(2, up))) up = k;
  }
  f.centre = box.base_T_box.translation().head<2>();
  for (int j = 0; j < 2; ++j) {
    const int k = (up + 1 + j) % 3;
    const Eigen::Vector2d a = R.col(k).head<2>();
    f.axis[j] = a.norm() > 1e-9 ? Eigen::Vector2d(a.normalized()) : Eigen::Vector2d::UnitX();
    f.half[j] = 0.5 * dims[k] * a.norm();
  }
  return f;
}

// How deep two footprints overlap: the smallest overlap of their
// projections over the four side directions (separating axes); <= 0 when
// they are apart.
double OverlapDepth(const Footprint& a, const Footprint& b) {
  double depth = std::numeric_limits<double>::infinity();
  for (const Footprint* f : {&a, &b}) {
    for (const Eigen::Vector2d& n : f->axis) {
      auto extent = [&](const Footprint& g) {
        return g.half[0] * std::abs(g.axis[0].dot(n)) + g.half[1] * std::abs(g.axis[1].dot(n));
      };
      const double ca = a.centre.dot(n), cb = b.centre.dot(n);
      const double ea = extent(a), eb = extent(b);
      depth = std::min(depth, std::min(ca + ea, cb + eb) - std::max(ca - ea, cb - eb));
    }
  }
  return depth;
}

// Why the pile contradicts box i (empty when it does not): it shares space
// with another box of its layer, or its grasp face is not the face most of
// its layer show (a wrong face size: its depth, and so its bottom, is off).
std::string CheckAgainstPile(size_t i, const std::vector<BoxVerdict>& verdicts,
                             const std::vector<Footprint>& footprints,
                             const SelectionOptions& selection,
                             const std::vector<double>& recent_depths) {
  const Footprint& f = footprints[i];
  std::vector<size_t> layer;
  for (size_t j = 0; j < footprints.size(); ++j) {
    if (std::abs(footprints[j].top_z - f.top_z) <= selection.layer_tolerance_m) layer.push_back(j);
  }
  for (size_t j : layer) {
    if (j == i) continue;
    const double depth = OverlapDepth(f, footprints[j]);
    if (depth > selection.max_overlap_m) {
      return absl::StrFormat("overlaps box #%d of its layer by %.3f m (max %.3f): one of the two "
                             "is misplaced",
                             verdicts[j].index, depth, selection.max_overlap_m);
    }
  }
  // The face check looks at the whole frame: the visible boxes of a pallet
  // (its top layer and the exposed edges of the ones below) lie alike.
  // The boxes in view and the last picks' grasp depths vote.
  std::vector<double> depths;
  for (const BoxVerdict& v : verdicts) depths.push_back(v.box.depth_m);
  const size_t history = std::min(recent_depths.size(),
                                  static_cast<size_t>(std::max(0, selection.face_check_history)));
  depths.insert(depths.end(), recent_depths.end() - history, recent_depths.end());
  const int votes = static_cast<int>(depths.size());
  if (selection.min_layer_for_face_check > 0 && votes >= selection.min_layer_for_face_check) {
    const double depth_i = verdicts[i].box.depth_m;
    int agree = 0;
    int best_agree = 0;
    double best_depth = depth_i;
    for (size_t j = 0; j < depths.size(); ++j) {
      int n = 0;
      for (double other : depths) n += std::abs(other - depths[j]) <= selection.layer_tolerance_m;
      if (j == i) agree = n;
      if (n > best_agree) {
        best_agree = n;
        best_depth = depths[j];
      }
    }
    // Declined only when a clear majority shows another face.
    if (3 * best_agree >= 2 * votes && agree < best_agree &&
        std::abs(best_depth - depth_i) > selection.layer_tolerance_m) {
      const int in_view = static_cast<int>(verdicts.size());
      return absl::StrFormat(
          "grasp face is %.3f m deep, but %d of the %d boxes in view%s show a face %.3f m deep: "
          "the wrong face size",
          depth_i, best_agree, votes,
          history > 0 ? absl::StrFormat(" (%d) and last picks (%d)", in_view, votes - in_view)
                      : std::string(),
          best_depth);
    }
  }
  return "";
}

}  // namespace

PickSelection SelectPick(const std::vector<DetectedBox>& boxes,
                         const Eigen::Isometry3d& base_T_camera, const BoxDims& dims,
                         const SelectionOptions& selection, const Workspace& workspace,
                         const WaypointOptions& waypoints, const Reachability& reachable,
                         const std::vector<double>& recent_depths) {
  PickSelection result;
  result.verdicts.reserve(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    BoxVerdict verdict;
    verdict.index = static_cast<int>(i);
    verdict.score = boxes[i].score;
    verdict.box = BoxToBase(boxes[i], base_T_camera, dims);
    result.verdicts.push_back(std::move(verdict));
  }
  // The pile's top: the highest point of any detected box.
  std::vector<Footprint> footprints;
  double pile_top = std::numeric_limits<double>::quiet_NaN();
  for (const BoxVerdict& v : result.verdicts) {
    footprints.push_back(FootprintOf(v.box, dims));
    if (!(pile_top >= footprints.back().top_z)) pile_top = footprints.back().top_z;
  }
  // A layer's boxes share one top: with at least three of one depth in a
  // layer, each grasp point takes the layer's median top, which averages
  // away the sensor's depth steps (about 1 cm at 1.4 m for a Kinect).
  std::vector<double> snap(boxes.size(), 0.0);
  for (size_t i = 0; i < boxes.size(); ++i) {
    std::vector<double> tops;
    for (size_t j = 0; j < boxes.size(); ++j) {
      if (std::abs(footprints[j].top_z - footprints[i].top_z) <= selection.layer_tolerance_m &&
          std::abs(result.verdicts[j].box.depth_m - result.verdicts[i].box.depth_m) <= 1e-3 &&
          result.verdicts[j].box.tilt_deg <= selection.max_grasp_tilt_deg) {
        tops.push_back(footprints[j].top_z);
      }
    }
    if (tops.size() < 3) continue;
    std::nth_element(tops.begin(), tops.begin() + tops.size() / 2, tops.end());
    snap[i] = tops[tops.size() / 2] - footprints[i].top_z;
  }
  for (size_t i = 0; i < boxes.size(); ++i) {
    BoxVerdict& verdict = result.verdicts[i];
    verdict.box.pile_top_z_m = pile_top;
    verdict.box.base_T_box.translation().z() += snap[i];
    verdict.box.grasp_point.z() += snap[i];
    if (!(boxes[i].score >= selection.min_score)) {
      verdict.reason = absl::StrFormat("score %.3f is below min_score %.3f", boxes[i].score,
                                       selection.min_score);
    } else if (!(verdict.box.tilt_deg <= selection.max_grasp_tilt_deg)) {
      verdict.reason = absl::StrFormat("grasp face tilted %.1f deg from base +z (max %.1f)",
                                       verdict.box.tilt_deg, selection.max_grasp_tilt_deg);
    } else if (std::string pile =
                   CheckAgainstPile(i, result.verdicts, footprints, selection, recent_depths);
               !pile.empty()) {
      verdict.reason = std::move(pile);
    } else {
      verdict.reason = CheckPickWaypoints(verdict.box, workspace, waypoints, reachable);
    }
    verdict.accepted = verdict.reason.empty();
  }

  // Repeatedly the best of the rest: the highest grasp point, ties within
  // height_tie_m of it decided by score, then height, then index.
  std::vector<const BoxVerdict*> rest;
  for (const BoxVerdict& v : result.verdicts) {
    if (v.accepted) rest.push_back(&v);
  }
  while (!rest.empty()) {
    double top_z = -std::numeric_limits<double>::infinity();
    for (const BoxVerdict* v : rest) top_z = std::max(top_z, v->box.grasp_point.z());
    auto best = rest.end();
    for (auto it = rest.begin(); it != rest.end(); ++it) {
      const BoxVerdict& v = **it;
      if (v.box.grasp_point.z() < top_z - selection.height_tie_m) continue;
      if (best == rest.end() || v.score > (*best)->score ||
          (v.score == (*best)->score && v.box.grasp_point.z() > (*best)->box.grasp_point.z())) {
        best = it;
      }
    }
    result.ranked.push_back((*best)->index);
    rest.erase(best);
  }
  if (!result.ranked.empty()) result.chosen = result.ranked.front();
  return result;
}

}  // namespace cornerpose::robot_client
