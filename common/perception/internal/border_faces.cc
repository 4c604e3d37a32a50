#include "common/perception/internal/border_faces.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "common/perception/internal/height_at.h"

namespace cornerpose::internal {
namespace {

// Sampling along a line of the face toward its side out of view. Metres.
constexpr double kStepM = 0.005;
// A line's samples on the face's plane, of those it has in view: over the
// whole line and over its decisive part (past every shorter side that could
// stand there). Unitless.
constexpr double kMinOnPlaneShare = 0.8;

bool Measured(SideKind k) { return k == SideKind::kFree || k == SideKind::kSeam; }

}  // namespace

int SideOutOfViewPinned(const DepthImage& depth, const Eigen::Isometry3d& camera_T_box,
                        BoxFace grasp, const BoxDims& dims, const RefinementResult& ref,
                        const AcceptanceOptions& o, double plane_tolerance_m) {
  int open = -1;
  for (int s = 0; s < 4; ++s) {
    if (Measured(ref.sides[s])) continue;
    if (open >= 0 || ref.sides[s] != SideKind::kUnknown) return -1;
    open = s;
  }
  if (open < 0) return -1;
  const int fi = static_cast<int>(grasp), n = fi / 2;
  const int here = open < 2 ? (n + 1) % 3 : (n + 2) % 3;
  const int other = open < 2 ? (n + 2) % 3 : (n + 1) % 3;
  const double tol = o.extent_tolerance_m;
  // The other lengths the face could have along `here` with the width it
  // has along `other` (measured between two ends): a longer one may go on
  // out of view (unpinned); the longest shorter one must be seen past.
  double shorter = 0.0;
  for (int p = 0; p < 3; ++p) {
    if (std::abs(dims[p] - dims[other]) > tol) continue;
    for (int q = 0; q < 3; ++q) {
      if (q == p || (p == other && q == here)) continue;
      if (dims[q] > dims[here] + tol) return -1;
      if (dims[q] < dims[here] - tol) shorter = std::max(shorter, dims[q]);
    }
  }
  const double sign = open % 2 == 0 ? 1.0 : -1.0;
  Eigen::Vector3d face_centre = Eigen::Vector3d::Zero();
  face_centre[n] = (fi % 2 == 0 ? 0.5 : -0.5) * dims[n];
  const Eigen::Vector3d normal = camera_T_box.linear() * BoxFaceNormal(grasp);
  const CameraIntrinsics& k = depth.camera;
  const double margin = o.border_margin_px;
  auto in_view = [&](const Eigen::Vector3d& q) {
    if (q.z() <= 0.05) return false;
    const Eigen::Vector2d px = Project(k, q);
    return px.x() >= margin && px.y() >= margin && px.x() <= k.width - 1 - margin &&
           px.y() <= k.height - 1 - margin;
  };
  double seen = std::numeric_limits<double>::infinity();
  bool any_past_shorter = false;
  for (const double w : {-0.3, 0.0, 0.3}) {
    // From the measured end (t = 0) toward the side out of view.
    int on = 0, samples = 0, decisive_on = 0, decisive = 0;
    double last_in_view = 0.0;
    // The run of samples with no return just before the border (an active
    // stereo camera returns nothing in a band along one side of its
    // image): the view ends where it starts.
    int no_return_run = 0, no_return_decisive = 0;
    double last_return = 0.0;
    for (double t = 0.5 * kStepM; t <= dims[here]; t += kStepM) {
      Eigen::Vector3d local = face_centre;
      local[here] = sign * (t - 0.5 * dims[here]);
      local[other] = w * dims[other];
      const Eigen::Vector3d q = camera_T_box * local;
      if (!in_view(q)) break;
      last_in_view = t;
      const std::optional<double> h = HeightAt(depth, q, normal);
      const bool on_plane = h && !std::isnan(*h) && std::abs(*h) <= plane_tolerance_m;
      const bool no_return = h && std::isnan(*h);
      ++samples;
      on += on_plane;
      if (t > shorter + tol) {
        ++decisive;
        decisive_on += on_plane;
      }
      if (no_return) {
        ++no_return_run;
        no_return_decisive += t > shorter + tol;
      } else {
        no_return_run = no_return_decisive = 0;
        last_return = t;
      }
    }
    // The line must leave the view before the face's side: that side is
    // out of view, not unseen in it.
    if (last_in_view >= dims[here] - kStepM) return -1;
    if (o.border_band_ends_view) {
      samples -= no_return_run;
      decisive -= no_return_decisive;
      last_in_view = last_return;
    }
    if (samples == 0 || on < kMinOnPlaneShare * samples) return -1;
    // Past every shorter side, on its plane: no other face of the box.
    // One line suffices (the border may cut the face aslant, and the
    // measured sides fix its turn); every line must be on the plane.
    any_past_shorter = any_past_shorter || shorter == 0.0 ||
                       (decisive >= 2 && decisive_on >= kMinOnPlaneShare * decisive &&
                        last_in_view > shorter + tol);
    seen = std::min(seen, last_in_view);
  }
  if (!any_past_shorter || seen < o.min_in_view_share * dims[here]) return -1;
  return open;
}

}  // namespace cornerpose::internal
