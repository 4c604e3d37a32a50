#include "common/perception/face_proposals.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/perception/internal/parallel.h"

namespace cornerpose {
namespace {

// How many faces of `size` laid side by side, 0 to max_gap_m apart, make a
// run of `extent`; 0 when no whole number does.
int FaceCount(double extent, double size, const FaceProposalOptions& o) {
  const int k = static_cast<int>(std::lround(extent / size));
  if (k < 1) return 0;
  const double slack = extent - k * size;
  return slack >= -o.size_tolerance_m && slack <= (k - 1) * o.max_gap_m + o.size_tolerance_m ? k
                                                                                             : 0;
}

std::string Describe(const FaceTiling& t, const BoxDims& dims) {
  return absl::StrFormat("%d x %d faces of %.3f x %.3f m", t.count_u, t.count_v, dims[t.axis_u],
                         dims[t.axis_v]);
}

// The 2D convex hull (Andrew's monotone chain), counter-clockwise.
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i - 1]) <= 0) --k;
    hull[k++] = p[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

Eigen::Isometry3d TilePose(const PlaneRectangle& rect, const FaceTiling& t, const BoxDims& dims,
                           double u, double v) {
  Eigen::Matrix3d R;
  R.col(t.normal_axis) = rect.normal;
  R.col(t.axis_u) = rect.axis_u;
  R.col(t.axis_v) = rect.axis_v;
  if (R.determinant() < 0.0) R.col(t.axis_v) = -rect.axis_v;  // the box is symmetric
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = R;
  pose.translation() =
      rect.centre + u * rect.axis_u + v * rect.axis_v - 0.5 * dims[t.normal_axis] * rect.normal;
  return pose;
}

}  // namespace

absl::Status FaceProposalOptions::Validate() const {
  if (absl::Status s = patches.Validate(); !s.ok()) return s;
  if (absl::Status s = seams.Validate(); !s.ok()) return s;
  if (absl::Status s = anchored.Validate(); !s.ok()) return s;
  if (absl::Status s = seam_split.Validate(); !s.ok()) return s;
  if (!(size_tolerance_m > 0.0 && size_tolerance_m <= 0.1) ||
      !(max_gap_m >= 0.0 && max_gap_m <= 0.05) ||
      !(max_view_angle_deg > 0.0 && max_view_angle_deg < 90.0) || max_tiles < 1 ||
      !(min_seam_support > 0.0 && min_seam_support <= 1.0) ||
      !(layer_match_m > 0.0 && layer_match_m <= 0.2) ||
      !(layer_match_deg > 0.0 && layer_match_deg <= 45.0) ||
      !(layer_min_fill > 0.0 && layer_min_fill <= 1.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "face proposal options out of range: size_tolerance_m=", size_tolerance_m,
        " (0, 0.1], max_gap_m=", max_gap_m, " [0, 0.05], max_view_angle_deg=", max_view_angle_deg,
        " (0, 90), max_tiles=", max_tiles, " >= 1, min_seam_support=", min_seam_support,
        " (0, 1], layer_match_m=", layer_match_m, " (0, 0.2], layer_match_deg=", layer_match_deg,
        " (0, 45], layer_min_fill=", layer_min_fill, " (0, 1]"));
  }
  if (!(min_eroded_share >= 0.0 && min_eroded_share <= 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("faces.min_eroded_share=", min_eroded_share, " is outside [0, 1]"));
  }
  return absl::OkStatus();
}

std::vector<FaceTiling> TilingsOf(double width_m, double height_m, const BoxDims& dims,
                                  const FaceProposalOptions& o) {
  std::vector<FaceTiling> out;
  for (int n = 0; n < 3; ++n) {
    const int a = (n + 1) % 3, b = (n + 2) % 3;
    for (const auto& [su, sv] : {std::pair{a, b}, std::pair{b, a}}) {
      FaceTiling t{n, su, sv, FaceCount(width_m, dims[su], o), FaceCount(height_m, dims[sv], o)};
      if (t.count_u == 0 || t.count_v == 0 || t.tiles() > o.max_tiles) continue;
      // Equal sides give the same tiling twice (the box's symmetries). The
      // lambda takes t's copies: clang 14 cannot capture structured bindings.
      const bool repeat = std::any_of(out.begin(), out.end(), [&](const FaceTiling& q) {
        return std::abs(dims[q.axis_u] - dims[t.axis_u]) < 1e-4 &&
               std::abs(dims[q.axis_v] - dims[t.axis_v]) < 1e-4 &&
               std::abs(dims[q.normal_axis] - dims[n]) < 1e-4;
      });
      if (!repeat) out.push_back(t);
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const FaceTiling& x, const FaceTiling& y) { return x.tiles() < y.tiles(); });
  return out;
}

PlaneRectangle OutlineRectangle(const PlanarPatch& patch) {
  PlaneRectangle rect;
  rect.normal = patch.normal;
  const Eigen::Vector3d e1 = patch.normal.unitOrthogonal();
  const Eigen::Vector3d e2 = patch.normal.cross(e1);
  std::vector<Eigen::Vector2d> flat;
  flat.reserve(patch.points.size());
  for (const Eigen::Vector3d& p : patch.points) {
    const Eigen::Vector3d d = p - patch.centroid;
    flat.emplace_back(d.dot(e1), d.dot(e2));
  }
  const std::vector<Eigen::Vector2d> hull = ConvexHull(flat);
  double best_area = std::numeric_limits<double>::max();
  for (size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d edge = hull[(i + 1) % hull.size()] - hull[i];
    if (edge.norm() < 1e-9) continue;
    const Eigen::Vector2d u = edge.normalized(), v(-u.y(), u.x());
    double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
    for (const Eigen::Vector2d& q : hull) {
      u0 = std::min(u0, q.dot(u));
      u1 = std::max(u1, q.dot(u));
      v0 = std::min(v0, q.dot(v));
      v1 = std::max(v1, q.dot(v));
    }
    const double area = (u1 - u0) * (v1 - v0);
    if (area >= best_area) continue;
    best_area = area;
    rect.axis_u = u.x() * e1 + u.y() * e2;
    rect.axis_v = v.x() * e1 + v.y() * e2;
    rect.width = u1 - u0;
    rect.height = v1 - v0;
    const Eigen::Vector2d c = 0.5 * (u0 + u1) * u + 0.5 * (v0 + v1) * v;
    rect.centre = patch.centroid + c.x() * e1 + c.y() * e2;
  }
  return rect;
}

std::vector<Eigen::Isometry3d> TilePoses(const PlaneRectangle& rect, const FaceTiling& t,
                                         const BoxDims& dims) {
  std::vector<Eigen::Isometry3d> out;
  // Tiles spread evenly over the outline, so the gaps share its slack.
  const double step_u = rect.width / t.count_u, step_v = rect.height / t.count_v;
  for (int i = 0; i < t.count_u; ++i) {
    for (int j = 0; j < t.count_v; ++j) {
      out.push_back(TilePose(rect, t, dims, -0.5 * rect.width + (i + 0.5) * step_u,
                             -0.5 * rect.height + (j + 0.5) * step_v));
    }
  }
  return out;
}

Eigen::Isometry3d FacePoseAt(const PlaneRectangle& rect, const Eigen::Vector3d& centre,
                             const FaceTiling& tiling, const BoxDims& dims) {
  PlaneRectangle face = rect;
  face.centre = centre;
  return TilePose(face, tiling, dims, 0.0, 0.0);
}

double SeamSupport(const DepthImage& image, const PlaneRectangle& rect, const FaceTiling& t,
                   const BoxDims& dims, const SeamCueOptions& options) {
  (void)dims;
  if (!image.has_grey() || t.tiles() < 2) return 0.0;
  const double step_u = rect.width / t.count_u, step_v = rect.height / t.count_v;
  const Eigen::Vector3d corner =
      rect.centre - 0.5 * rect.width * rect.axis_u - 0.5 * rect.height * rect.axis_v;
  int sides = 0, seams = 0;
  // Lines between columns (across u), one side per row; then between rows.
  for (int i = 1; i < t.count_u; ++i) {
    for (int j = 0; j < t.count_v; ++j) {
      const Eigen::Vector3d a = corner + i * step_u * rect.axis_u + j * step_v * rect.axis_v;
      ++sides;
      seams += ColourSeamAlong(image, a, a + step_v * rect.axis_v, rect.axis_u, options).seam;
    }
  }
  for (int j = 1; j < t.count_v; ++j) {
    for (int i = 0; i < t.count_u; ++i) {
      const Eigen::Vector3d a = corner + i * step_u * rect.axis_u + j * step_v * rect.axis_v;
      ++sides;
      seams += ColourSeamAlong(image, a, a + step_u * rect.axis_u, rect.axis_v, options).seam;
    }
  }
  return sides > 0 ? static_cast<double>(seams) / sides : 0.0;
}

namespace {

// What one patch proposes (ProposeFromFaces gathers them in patch order).
struct PatchProposals {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<DeclinedCandidate> declined;
  std::vector<LayerTiles> layers;
};

// The faces, layer tiles and ambiguous tilings of patch `id`.
void ProposeFromPatch(const DepthImage& image, const PlanarPatches& patches, size_t id,
                      const BoxDims& dims, const FaceProposalOptions& o, PatchProposals* out_ptr) {
  PatchProposals& out = *out_ptr;
  std::array<double, 3> sorted = {dims.l, dims.b, dims.h};
  std::sort(sorted.begin(), sorted.end());
  const double smallest_face = sorted[0] * sorted[1];
  const double cos_view = std::cos(o.max_view_angle_deg * std::numbers::pi / 180.0);
  auto anchor_and_split = [&](const PlaneRectangle& rect, double cell_m) {
    const std::vector<Eigen::Isometry3d> faces =
        AnchoredFaces(patches.patches[id], rect, cell_m, image.camera, dims, o.anchored);
    out.poses.insert(out.poses.end(), faces.begin(), faces.end());
    const std::vector<Eigen::Isometry3d> split =
        SeamSplitFaces(image, patches, static_cast<int>(id), rect, dims, o.seam_split);
    out.poses.insert(out.poses.end(), split.begin(), split.end());
  };
  const PlanarPatch& patch = patches.patches[id];
  const double cell_m = patch.centroid.z() / image.camera.fx * patches.step_px;
  // Its area on its plane (a face slanted to the view covers 1/cos of what
  // its cells count), but only inside the view: a patch the image border
  // cuts keeps the count of its cells, the stricter test (with its slanted
  // area, a wooden cabinet panel at the top of a real YCB-V frame, 60
  // degrees to the view, proposed a box-sized face that the judge took).
  const double area = patch.touches_border ? PatchCellsArea(patch, image.camera.fx, patches.step_px)
                                           : PatchArea(patch, image.camera.fx, patches.step_px);
  if (area < 0.5 * smallest_face) return;
  if (patch.normal.dot(-patch.centroid.normalized()) < cos_view) return;
  const PlaneRectangle rect = OutlineRectangle(patch);
  // An outline cut by the image border says nothing about where a layer
  // ends. One no bigger than a face may still be that face whole (a box
  // near the edge of the view, its patch within a window of the border):
  // it proposes faces of the box on it, never a layer, and the judge
  // decides whether every side was seen (AcceptanceOptions).
  const double largest_side = sorted[2] + o.size_tolerance_m;
  const bool at_border = patch.touches_border;
  // One bigger than a face (a layer, a heap's top) may still have corners
  // inside the view (faces anchored there) and seams across it (faces
  // split out along them).
  if (at_border &&
      (!o.propose_at_border || rect.width > largest_side || rect.height > largest_side)) {
    if (o.propose_at_border) anchor_and_split(rect, cell_m);
    return;
  }
  // A patch filling little of its outline is no face or layer (a floor
  // around things, an L of two boxes' sides).
  if (area < 0.5 * rect.width * rect.height) return;
  // A tile is proposed only where the patch is (a layer can be notched
  // where boxes were taken).
  auto on_patch = [&](const Eigen::Isometry3d& pose, const FaceTiling& t) {
    const Eigen::Vector3d face_centre =
        pose.translation() + 0.5 * dims[t.normal_axis] * rect.normal;
    if (face_centre.z() <= 0.05) return false;
    const Eigen::Vector2d px = Project(image.camera, face_centre);
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    for (int dv = -1; dv <= 1; ++dv) {
      for (int du = -1; du <= 1; ++du) {
        if (patches.PatchAt(u + du * patches.step_px, v + dv * patches.step_px) ==
            static_cast<int>(id)) {
          return true;
        }
      }
    }
    return false;
  };
  auto propose = [&](const FaceTiling& t) {
    for (const Eigen::Isometry3d& pose : TilePoses(rect, t, dims)) {
      if (on_patch(pose, t)) out.poses.push_back(pose);
    }
  };
  // The tiles a box on this patch may be (every tile of the tilings in
  // play, on the patch or not: a notch is where a box was taken).
  auto in_play = [&](std::initializer_list<FaceTiling> in) {
    if (at_border) return;
    // Fill: the patch's area over that of the tiles on it (a layer with
    // boxes taken away is still full where it is); the least of the
    // tilings in play.
    LayerTiles layer{
        static_cast<int>(id), std::numeric_limits<double>::max(), patch.normal, patch.centroid, {}};
    for (const FaceTiling& t : in) {
      int present = 0;
      for (const Eigen::Isometry3d& pose : TilePoses(rect, t, dims)) {
        layer.tiles.push_back(pose);
        present += on_patch(pose, t);
      }
      const double tile_area = dims[t.axis_u] * dims[t.axis_v];
      layer.fill = std::min(layer.fill, present > 0 ? area / (present * tile_area) : 0.0);
    }
    out.layers.push_back(std::move(layer));
  };
  // A face bigger than the outline on one of its axes (past the tolerance)
  // but at least min_eroded_share of it on both: a face whose rim the
  // segmentation took in (a stereo camera's noise, rounded edges) is
  // centred on its outline.
  auto bigger_than_outline = [&](const FaceTiling& t) {
    return dims[t.axis_u] > rect.width + o.size_tolerance_m ||
           dims[t.axis_v] > rect.height + o.size_tolerance_m;
  };
  auto propose_eroded = [&](const FaceTiling& t) {
    if (o.min_eroded_share > 0.0 && rect.width >= o.min_eroded_share * dims[t.axis_u] &&
        rect.height >= o.min_eroded_share * dims[t.axis_v]) {
      const Eigen::Isometry3d pose = TilePose(rect, t, dims, 0.0, 0.0);
      if (on_patch(pose, t)) out.poses.push_back(pose);
    }
  };
  const std::vector<FaceTiling> tilings = TilingsOf(rect.width, rect.height, dims, o);
  if (tilings.empty()) {
    // For the layer check only (nothing is proposed from it): an outline
    // a little too big to tile (its rim taken in, noise at a closer
    // range) still makes a layer with twice the tolerance, when one
    // tiling has the fewest tiles; an anchor must confirm it (detector).
    FaceProposalOptions loose = o;
    loose.size_tolerance_m = 2.0 * o.size_tolerance_m;
    const std::vector<FaceTiling> near = TilingsOf(rect.width, rect.height, dims, loose);
    if (near.size() == 1 || (near.size() > 1 && near[0].tiles() < near[1].tiles())) {
      in_play({near[0]});
    }
    // Not a whole number of faces (part of it hidden or out of view): a
    // face in each corner of the outline, for each way one fits in it;
    // only for an outline about one face in size (a bigger one is a
    // floor, a wall, a layer cut by the image border).
    if (rect.width > largest_side || rect.height > largest_side) {
      anchor_and_split(rect, cell_m);
      return;
    }
    for (int n = 0; n < 3; ++n) {
      const int a = (n + 1) % 3, b = (n + 2) % 3;
      for (const auto& [su, sv] : {std::pair{a, b}, std::pair{b, a}}) {
        const FaceTiling t{n, su, sv, 1, 1};
        if (bigger_than_outline(t)) {
          propose_eroded(t);
          continue;
        }
        for (double cu : {-1.0, 1.0}) {
          for (double cv : {-1.0, 1.0}) {
            const Eigen::Isometry3d pose =
                TilePose(rect, t, dims, cu * 0.5 * (rect.width - dims[su]),
                         cv * 0.5 * (rect.height - dims[sv]));
            if (on_patch(pose, t)) out.poses.push_back(pose);
          }
        }
      }
    }
    return;
  }
  if (tilings.size() == 1) {
    propose(tilings[0]);
    in_play({tilings[0]});
    // Also a face of the box it is most of, its rim taken in
    // (FaceProposalOptions::eroded_beside_tile).
    for (int n = 0; n < 3 && o.eroded_beside_tile; ++n) {
      if (n == tilings[0].normal_axis) continue;
      const int a = (n + 1) % 3, b = (n + 2) % 3;
      for (const auto& [su, sv] : {std::pair{a, b}, std::pair{b, a}}) {
        const FaceTiling t{n, su, sv, 1, 1};
        if (bigger_than_outline(t)) propose_eroded(t);
      }
    }
    return;
  }
  // Several tilings fit: seam cues first, then the fewest boxes.
  std::vector<double> support(tilings.size(), 0.0);
  for (size_t i = 0; i < tilings.size(); ++i) {
    support[i] = SeamSupport(image, rect, tilings[i], dims, o.seams);
  }
  const size_t best = std::max_element(support.begin(), support.end()) - support.begin();
  int chosen = -1;
  if (support[best] >= o.min_seam_support) {
    bool alone = true;
    for (size_t i = 0; i < tilings.size(); ++i) {
      if (i != best && support[i] > support[best] - o.seam_support_margin) alone = false;
    }
    if (alone) chosen = static_cast<int>(best);
  } else if (tilings[0].tiles() < tilings[1].tiles()) {
    chosen = 0;
  }
  if (chosen >= 0) {
    propose(tilings[chosen]);
    in_play({tilings[chosen]});
    return;
  }
  in_play({tilings[0], tilings[1]});
  for (size_t i = 0; i < tilings.size() && i < 2; ++i) {
    DeclinedCandidate d;
    d.camera_T_box = TilePoses(rect, tilings[i], dims).front();
    d.reason = absl::StrFormat(
        "face %.3f x %.3f m tiles two ways (%s, or %s) and no seam cue decides", rect.width,
        rect.height, Describe(tilings[0], dims), Describe(tilings[1], dims));
    out.declined.push_back(d);
  }
}

}  // namespace

bool ExcludedPlane::Holds(const PlanarPatch& patch) const {
  return patch.normal.dot(normal) >= std::cos(max_angle_deg * std::numbers::pi / 180.0) &&
         std::abs(normal.dot(patch.centroid - point)) <= max_distance_m;
}

FaceProposals ProposeFromFaces(const DepthImage& image, const BoxDims& dims,
                               const FaceProposalOptions& o, const CancelToken* cancel,
                               internal::SharedLoops* helpers, const ExcludedPlaneFinder& exclude) {
  FaceProposals out;
  PlanarPatches pieces;
  out.patches = SegmentPlanarPatches(image, o.patches, o.propose_merged_pieces ? &pieces : nullptr);
  const PlanarPatches& patches = out.patches;
  out.num_patches = static_cast<int>(patches.patches.size());
  const std::optional<ExcludedPlane> excluded = exclude ? exclude(patches) : std::nullopt;
  // Patch by patch, then piece by piece, each into its own slot (with
  // helpers, in any order on any thread), gathered in that order: the same
  // proposals either way.
  const int n = static_cast<int>(patches.patches.size());
  std::vector<PatchProposals> per_patch(n + pieces.patches.size());
  auto propose = [&](int begin, int end) {
    for (int id = begin; id < end && !StopRequested(cancel); ++id) {
      const PlanarPatch& patch = id < n ? patches.patches[id] : pieces.patches[id - n];
      if (excluded && excluded->Holds(patch)) continue;
      if (id < n) {
        ProposeFromPatch(image, patches, id, dims, o, &per_patch[id]);
      } else {
        ProposeFromPatch(image, pieces, id - n, dims, o, &per_patch[id]);
      }
    }
  };
  const int all = static_cast<int>(per_patch.size());
  if (helpers != nullptr) {
    helpers->Run(all, 1, propose);
  } else {
    propose(0, all);
  }
  for (int id = 0; id < all; ++id) {
    PatchProposals& p = per_patch[id];
    out.poses.insert(out.poses.end(), p.poses.begin(), p.poses.end());
    if (id >= n) continue;  // a piece: its poses only
    out.declined.insert(out.declined.end(), p.declined.begin(), p.declined.end());
    for (LayerTiles& l : p.layers) out.layers.push_back(std::move(l));
  }
  return out;
}

namespace {

// Whether two poses are the same box: centres close, and each axis of `a`
// parallel to an axis of `b` of the same size (the box's symmetries).
bool SameBox(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const BoxDims& dims,
             double max_distance_m, double max_angle_deg) {
  if ((a.translation() - b.translation()).norm() > max_distance_m) return false;
  const double cos_max = std::cos(max_angle_deg * std::numbers::pi / 180.0);
  for (int i = 0; i < 3; ++i) {
    bool matched = false;
    for (int j = 0; j < 3 && !matched; ++j) {
      matched = std::abs(a.linear().col(i).dot(b.linear().col(j))) >= cos_max &&
                std::abs(dims[i] - dims[j]) < 1e-4;
    }
    if (!matched) return false;
  }
  return true;
}

}  // namespace

int LayerUnder(const FaceProposals& faces, const DepthImage& image,
               const Eigen::Vector3d& face_centre, const Eigen::Vector3d& face_normal,
               const FaceProposalOptions& o) {
  if (faces.layers.empty() || face_centre.z() <= 0.05) return -1;
  const Eigen::Vector2d px = Project(image.camera, face_centre);
  const int patch = faces.patches.PatchAt(static_cast<int>(std::lround(px.x())),
                                          static_cast<int>(std::lround(px.y())));
  if (patch < 0) return -1;
  const double cos_max = std::cos(o.layer_match_deg * std::numbers::pi / 180.0);
  for (size_t i = 0; i < faces.layers.size(); ++i) {
    const LayerTiles& layer = faces.layers[i];
    if (layer.patch != patch) continue;
    if (layer.fill < o.layer_min_fill || std::abs(face_normal.dot(layer.normal)) < cos_max ||
        std::abs((face_centre - layer.centroid).dot(layer.normal)) > o.layer_match_m) {
      return -1;
    }
    return static_cast<int>(i);
  }
  return -1;
}

bool IsLayerTile(const LayerTiles& layer, const BoxDims& dims,
                 const Eigen::Isometry3d& camera_T_box, const FaceProposalOptions& o) {
  return std::any_of(layer.tiles.begin(), layer.tiles.end(), [&](const Eigen::Isometry3d& tile) {
    return SameBox(camera_T_box, tile, dims, o.layer_match_m, o.layer_match_deg);
  });
}

}  // namespace cornerpose
