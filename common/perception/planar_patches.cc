#include "common/perception/planar_patches.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <numeric>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

// Running sums of points for a plane fit.
// A piece holding this share of its merged patch's cells is not listed
// among the merged pieces (MergeCoplanarPatches).
constexpr double kWholePieceShare = 0.95;

struct Moments {
  double n = 0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
  void Add(const Eigen::Vector3d& p) {
    n += 1;
    s += p;
    ss += p * p.transpose();
  }
  // Normal (smallest eigenvector, towards the camera), centroid, and the
  // eigenvalues ascending.
  void Fit(Eigen::Vector3d* normal, Eigen::Vector3d* centroid, Eigen::Vector3d* eig) const {
    *centroid = s / n;
    const Eigen::Matrix3d cov = ss / n - *centroid * centroid->transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(cov);
    *normal = solver.eigenvectors().col(0);
    if (normal->dot(*centroid) > 0) *normal = -*normal;
    *eig = solver.eigenvalues().cwiseMax(0.0);
  }
};

// Union-find over patch ids.
int Root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Joins patches that lie within merge_gap_cells of each other on one plane:
// a face that noise broke into pieces (an active-stereo camera's smoothing
// leaves low bumps whose cell normals stray past max_normal_angle_deg, and
// the cells between pieces fail the flatness test). Each pair is judged on
// the pieces' fitted planes, which average out what split them: normals
// within merge_angle_deg, and each centroid on the other's plane within
// the growth tolerance. Largest shared boundary first; a joined patch is
// refitted before it is compared again.
template <typename Tolerance>
void MergeCoplanarPatches(const PlanarPatchOptions& o, const Tolerance& tolerance,
                          PlanarPatches* out, PlanarPatches* pieces) {
  const int n = static_cast<int>(out->patches.size());
  if (n < 2) return;
  const int W = out->cells_wide, H = out->cells_high, g = o.merge_gap_cells;
  // Pairs of patches with cells within g of each other, with how many.
  std::vector<std::pair<uint64_t, int>> pairs;
  {
    std::vector<uint64_t> keys;
    for (int cv = 0; cv < H; ++cv) {
      for (int cu = 0; cu < W; ++cu) {
        const int a = out->label[static_cast<size_t>(cv) * W + cu];
        if (a < 0) continue;
        // Right and down only (and the diagonals down): each pair once.
        for (int dv = 0; dv <= g; ++dv) {
          for (int du = -g; du <= g; ++du) {
            if (dv == 0 && du <= 0) continue;
            const int u = cu + du, v = cv + dv;
            if (u < 0 || u >= W || v >= H) continue;
            const int b = out->label[static_cast<size_t>(v) * W + u];
            if (b < 0 || b == a) continue;
            keys.push_back(static_cast<uint64_t>(std::min(a, b)) << 32 |
                           static_cast<uint32_t>(std::max(a, b)));
          }
        }
      }
    }
    std::sort(keys.begin(), keys.end());
    for (size_t i = 0; i < keys.size();) {
      size_t j = i;
      while (j < keys.size() && keys[j] == keys[i]) ++j;
      pairs.push_back({keys[i], static_cast<int>(j - i)});
      i = j;
    }
  }
  if (pairs.empty()) return;
  std::sort(pairs.begin(), pairs.end(),
            [](const auto& x, const auto& y) { return x.second > y.second; });
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<Moments> moments(n);
  std::vector<Eigen::Vector3d> normal(n), centroid(n);
  for (int i = 0; i < n; ++i) {
    for (const Eigen::Vector3d& p : out->patches[i].points) moments[i].Add(p);
    normal[i] = out->patches[i].normal;
    centroid[i] = out->patches[i].centroid;
  }
  const double cos_max = std::cos(o.merge_angle_deg * M_PI / 180.0);
  bool merged = false;
  for (const auto& [key, count] : pairs) {
    const int a = Root(parent, static_cast<int>(key >> 32)),
              b = Root(parent, static_cast<int>(key & 0xffffffffu));
    if (a == b) continue;
    if (normal[a].dot(normal[b]) < cos_max) continue;
    if (std::abs(normal[a].dot(centroid[b] - centroid[a])) > tolerance(centroid[b].z()) ||
        std::abs(normal[b].dot(centroid[a] - centroid[b])) > tolerance(centroid[a].z())) {
      continue;
    }
    parent[b] = a;
    moments[a].n += moments[b].n;
    moments[a].s += moments[b].s;
    moments[a].ss += moments[b].ss;
    Eigen::Vector3d eig;
    moments[a].Fit(&normal[a], &centroid[a], &eig);
    merged = true;
  }
  if (!merged) return;
  // Renumber: each root keeps the first id among its members. A patch
  // joined with none is kept as it is; a joined one is refitted on all its
  // points.
  std::vector<int> members(n, 0);
  for (int i = 0; i < n; ++i) ++members[Root(parent, i)];
  if (pieces != nullptr) {
    pieces->cells_wide = W;
    pieces->cells_high = H;
    pieces->step_px = out->step_px;
    pieces->label.assign(out->label.size(), -1);
    std::vector<int> piece_id(n, -1);
    for (int i = 0; i < n; ++i) {
      const int root = Root(parent, i);
      if (members[root] == 1) continue;
      // Nearly all of its patch (crumbs merged into it): its outline, and
      // so its faces, are the patch's.
      if (static_cast<double>(out->patches[i].points.size()) >=
          kWholePieceShare * moments[root].n) {
        continue;
      }
      piece_id[i] = static_cast<int>(pieces->patches.size());
      pieces->patches.push_back(out->patches[i]);
    }
    for (size_t c = 0; c < out->label.size(); ++c) {
      if (out->label[c] >= 0) pieces->label[c] = piece_id[out->label[c]];
    }
  }
  std::vector<int> new_id(n, -1);
  std::vector<PlanarPatch> patches;
  for (int i = 0; i < n; ++i) {
    const int root = Root(parent, i);
    if (new_id[root] < 0) {
      new_id[root] = static_cast<int>(patches.size());
      patches.emplace_back();
    }
    new_id[i] = new_id[root];
    PlanarPatch& p = patches[new_id[i]];
    PlanarPatch& from = out->patches[i];
    if (members[root] == 1) {
      p = std::move(from);
      continue;
    }
    p.touches_border |= from.touches_border;
    p.points.insert(p.points.end(), from.points.begin(), from.points.end());
  }
  for (int i = 0; i < n; ++i) {
    if (Root(parent, i) != i || members[i] == 1) continue;
    PlanarPatch& p = patches[new_id[i]];
    Moments all;
    for (const Eigen::Vector3d& q : p.points) all.Add(q);
    Eigen::Vector3d eig;
    all.Fit(&p.normal, &p.centroid, &eig);
    p.rms_m = std::sqrt(eig(0));
  }
  for (int& l : out->label) {
    if (l >= 0) l = new_id[l];
  }
  out->patches = std::move(patches);
}

}  // namespace

absl::Status PlanarPatchOptions::Validate() const {
  if (step_px < 1 || step_px > 8 || window_cells < 1 || window_cells > 8 ||
      !(max_curvature > 0.0 && max_curvature < 1.0 / 3.0) ||
      !(max_normal_angle_deg > 0.0 && max_normal_angle_deg < 90.0) ||
      !(plane_tolerance_base_m > 0.0 && plane_tolerance_base_m < 0.1) ||
      !(plane_tolerance_per_m2 >= 0.0 && plane_tolerance_per_m2 < 0.1) || min_cells < 4 ||
      merge_gap_cells < 0 || merge_gap_cells > 8 ||
      !(merge_angle_deg > 0.0 && merge_angle_deg < 90.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "planar patch options out of range: step_px=", step_px,
        " [1, 8], window_cells=", window_cells, " [1, 8], max_curvature=", max_curvature,
        " (0, 1/3), max_normal_angle_deg=", max_normal_angle_deg,
        " (0, 90), plane_tolerance_base_m=", plane_tolerance_base_m,
        " (0, 0.1), plane_tolerance_per_m2=", plane_tolerance_per_m2,
        " [0, 0.1), min_cells=", min_cells, " >= 4, merge_gap_cells=", merge_gap_cells,
        " [0, 8], merge_angle_deg=", merge_angle_deg, " (0, 90)"));
  }
  return absl::OkStatus();
}

double PatchCellsArea(const PlanarPatch& patch, double fx, int step_px) {
  const double cell_m = patch.centroid.z() / fx * step_px;
  return static_cast<double>(patch.points.size()) * cell_m * cell_m;
}

double PatchArea(const PlanarPatch& patch, double fx, int step_px) {
  const double norm = patch.centroid.norm();
  const double cos_slant = norm > 0.0 ? std::abs(patch.normal.dot(patch.centroid)) / norm : 1.0;
  constexpr double kMinCos = 0.17364817766693033;  // cos(80 degrees)
  return PatchCellsArea(patch, fx, step_px) / std::max(cos_slant, kMinCos);
}

PlanarPatches SegmentPlanarPatches(const DepthImage& depth, const PlanarPatchOptions& o,
                                   PlanarPatches* merged_pieces) {
  PlanarPatches out;
  if (merged_pieces != nullptr) *merged_pieces = PlanarPatches();
  const CameraIntrinsics& k = depth.camera;
  const int s = o.step_px;
  const int W = k.width / s, H = k.height / s;
  out.cells_wide = W;
  out.cells_high = H;
  out.step_px = s;
  out.label.assign(static_cast<size_t>(W) * H, -1);
  if (W < 3 || H < 3 || depth.z.size() != static_cast<size_t>(k.width) * k.height) return out;
  const size_t N = static_cast<size_t>(W) * H;
  // The cell's point: the pixel at its centre.
  std::vector<Eigen::Vector3d> point(N);
  std::vector<char> valid(N, 0);
  for (int cv = 0; cv < H; ++cv) {
    for (int cu = 0; cu < W; ++cu) {
      const int u = cu * s + s / 2, v = cv * s + s / 2;
      const float z = depth.at(u, v);
      if (std::isnan(z) || z <= 0.0f) continue;
      const size_t i = static_cast<size_t>(cv) * W + cu;
      point[i] = static_cast<double>(z) * PixelRay(k, u, v);
      valid[i] = 1;
    }
  }
  // Integral images of the point moments: 1, x, y, z, xx, xy, xz, yy, yz, zz,
  // row by row: a window needs only the rows r above and r + 1 below its
  // centre, so the last 2r + 2 rows are kept in a ring (a whole frame's
  // integral was 1.5 MB, most of a cold frame's page faults in this stage).
  constexpr int kM = 10;
  const int r = o.window_cells;
  const int ring_rows = 2 * r + 2;
  std::vector<double> ring(static_cast<size_t>(ring_rows) * (W + 1) * kM, 0.0);
  auto at = [&](int cu, int cv) {
    return &ring[(static_cast<size_t>(cv % ring_rows) * (W + 1) + cu) * kM];
  };
  int integral_rows = 1;         // rows [0, integral_rows) made; row 0 is all zeros
  auto make_row = [&](int cv) {  // integral row cv + 1, from cell row cv
    double row[kM] = {};
    std::fill_n(at(0, cv + 1), kM, 0.0);
    for (int cu = 0; cu < W; ++cu) {
      const size_t i = static_cast<size_t>(cv) * W + cu;
      if (valid[i]) {
        const Eigen::Vector3d& p = point[i];
        const double m[kM] = {1,
                              p.x(),
                              p.y(),
                              p.z(),
                              p.x() * p.x(),
                              p.x() * p.y(),
                              p.x() * p.z(),
                              p.y() * p.y(),
                              p.y() * p.z(),
                              p.z() * p.z()};
        for (int j = 0; j < kM; ++j) row[j] += m[j];
      }
      double* dst = at(cu + 1, cv + 1);
      const double* up = at(cu + 1, cv);
      for (int j = 0; j < kM; ++j) dst[j] = up[j] + row[j];
    }
  };
  // Per cell: the window's normal and curvature.
  const int min_window = (2 * r + 1) * (2 * r + 1) / 2;
  std::vector<Eigen::Vector3f> normal(N, Eigen::Vector3f::Zero());
  std::vector<float> curvature(N, 1.0f);
  for (int cv = r; cv < H - r; ++cv) {
    while (integral_rows <= cv + r + 1) make_row(integral_rows++ - 1);
    for (int cu = r; cu < W - r; ++cu) {
      const size_t i = static_cast<size_t>(cv) * W + cu;
      if (!valid[i]) continue;
      const double *a = at(cu - r, cv - r), *b = at(cu + r + 1, cv - r),
                   *c = at(cu - r, cv + r + 1), *d = at(cu + r + 1, cv + r + 1);
      double m[kM];
      for (int j = 0; j < kM; ++j) m[j] = d[j] - b[j] - c[j] + a[j];
      if (m[0] < min_window) continue;
      Moments mo;
      mo.n = m[0];
      mo.s = {m[1], m[2], m[3]};
      mo.ss << m[4], m[5], m[6], m[5], m[7], m[8], m[6], m[8], m[9];
      Eigen::Vector3d n, centroid, eig;
      mo.Fit(&n, &centroid, &eig);
      const double sum = eig.sum();
      if (!(sum > 0.0)) continue;
      normal[i] = n.cast<float>();
      curvature[i] = static_cast<float>(eig(0) / sum);
    }
  }
  // Seeds flattest first.
  std::vector<int> order;
  for (size_t i = 0; i < N; ++i) {
    if (curvature[i] < o.max_curvature) order.push_back(static_cast<int>(i));
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return curvature[a] < curvature[b]; });
  const double cos_max = std::cos(o.max_normal_angle_deg * M_PI / 180.0);
  auto tolerance = [&](double z) {
    return o.plane_tolerance_base_m + o.plane_tolerance_per_m2 * z * z;
  };
  std::vector<int> members;
  std::deque<int> queue;
  for (int seed : order) {
    if (out.label[seed] != -1) continue;
    const int id = static_cast<int>(out.patches.size());
    Moments mo;
    Eigen::Vector3d n = normal[seed].cast<double>(), c = point[seed];
    members.clear();
    queue.clear();
    queue.push_back(seed);
    out.label[seed] = id;
    double refit_at = 16;
    while (!queue.empty()) {
      const int i = queue.front();
      queue.pop_front();
      members.push_back(i);
      mo.Add(point[i]);
      if (mo.n >= refit_at) {  // the plane follows the region as it grows
        Eigen::Vector3d eig;
        mo.Fit(&n, &c, &eig);
        refit_at *= 1.5;
      }
      const int cu = i % W, cv = i / W;
      const int nbs[4][2] = {{cu + 1, cv}, {cu - 1, cv}, {cu, cv + 1}, {cu, cv - 1}};
      for (const auto& nb : nbs) {
        if (nb[0] < 0 || nb[1] < 0 || nb[0] >= W || nb[1] >= H) continue;
        const int j = nb[1] * W + nb[0];
        if (out.label[j] != -1 || curvature[j] >= o.max_curvature) continue;
        if (normal[j].cast<double>().dot(n) < cos_max) continue;
        if (std::abs(n.dot(point[j] - c)) > tolerance(point[j].z())) continue;
        out.label[j] = id;
        queue.push_back(j);
      }
    }
    // The rim: valid cells next to the region whose point lies on its
    // plane, up to the window's half size out.
    std::vector<int> frontier = members;
    for (int ring = 0; ring <= r && !frontier.empty(); ++ring) {
      std::vector<int> next;
      for (int i : frontier) {
        const int cu = i % W, cv = i / W;
        const int nbs[4][2] = {{cu + 1, cv}, {cu - 1, cv}, {cu, cv + 1}, {cu, cv - 1}};
        for (const auto& nb : nbs) {
          if (nb[0] < 0 || nb[1] < 0 || nb[0] >= W || nb[1] >= H) continue;
          const int j = nb[1] * W + nb[0];
          if (out.label[j] != -1 || !valid[j]) continue;
          if (std::abs(n.dot(point[j] - c)) > 0.5 * tolerance(point[j].z())) continue;
          out.label[j] = id;
          next.push_back(j);
          members.push_back(j);
        }
      }
      frontier = std::move(next);
    }
    if (static_cast<int>(members.size()) < o.min_cells) {
      for (int i : members) out.label[i] = -2;  // taken, but no patch
      continue;
    }
    PlanarPatch patch;
    Moments all;
    patch.points.reserve(members.size());
    for (int i : members) {
      const int cu = i % W, cv = i / W;
      patch.touches_border |= cu <= r || cv <= r || cu >= W - 1 - r || cv >= H - 1 - r;
      patch.points.push_back(point[i]);
      all.Add(point[i]);
    }
    Eigen::Vector3d eig;
    all.Fit(&patch.normal, &patch.centroid, &eig);
    patch.rms_m = std::sqrt(eig(0));
    out.patches.push_back(std::move(patch));
  }
  for (int& l : out.label) l = std::max(l, -1);
  if (o.merge_gap_cells > 0) MergeCoplanarPatches(o, tolerance, &out, merged_pieces);
  return out;
}

}  // namespace cornerpose
