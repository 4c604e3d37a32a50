#include "common/perception/box_refinement.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "common/perception/internal/height_at.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

using internal::HeightAt;

double Median(std::vector<double>& v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct FacePoint {
  double a, b, n;  // coordinates in the face frame, metres
};

// The face frame: centre c, outward normal n, in-plane axes a and b.
struct FaceFrame {
  Eigen::Vector3d c, n, a, b;
  double half_a, half_b;
  int axis_a, axis_b, axis_n;
  double sign_n;
};

FaceFrame MakeFaceFrame(const Eigen::Isometry3d& camera_T_box, const BoxDims& dims, BoxFace face) {
  FaceFrame f;
  const int fi = static_cast<int>(face);
  f.axis_n = fi / 2;
  f.sign_n = fi % 2 == 0 ? 1.0 : -1.0;
  f.axis_a = (f.axis_n + 1) % 3;
  f.axis_b = (f.axis_n + 2) % 3;
  const Eigen::Matrix3d R = camera_T_box.linear();
  f.n = f.sign_n * R.col(f.axis_n);
  f.a = R.col(f.axis_a);
  f.b = R.col(f.axis_b);
  f.half_a = dims[f.axis_a] / 2.0;
  f.half_b = dims[f.axis_b] / 2.0;
  f.c = camera_T_box.translation() + f.n * dims[f.axis_n] / 2.0;
  return f;
}

// Measured points near the face, in face coordinates, as the refinement
// reads them: the plane fit reads the interior, each side's measurement
// only the band along it, so each side gets its own copy of its band
// (every point with sign * coordinate >= half - margin, in pixel order; a
// corner's points are in two bands). Per side: the points on the plane,
// the points in front of it (an occluder) and where every pixel's ray meets
// the plane (what a fully seen face would give: the reference for point
// densities; its n says what that pixel returned: grid_return).
struct FacePoints {
  // The points on the plane >= 1 cm inside every side, as their count and
  // the sums of their coordinates and products (all the plane fit needs).
  int interior = 0;
  // How deep a groove along a side must be to make a seam
  // (RefinementOptions::min_seam_depth_m, seam_depth_per_rms), set once the
  // plane is fitted.
  double seam_depth_m = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_outer = Eigen::Matrix3d::Zero();
  std::array<std::vector<FacePoint>, 4> on_plane, front, grid;  // +a, -a, +b, -b bands
};

// What a pixel of the ray-plane grid returned, as its FacePoint's n.
namespace grid_return {
constexpr double kOnPlane = 1.0;
constexpr double kBehind = -1.0;  // a point behind the plane: it is not there
constexpr double kInFront = 0.5;  // a point in front of it, hiding it
constexpr double kNothing = 0.0;  // no return
}  // namespace grid_return

// Side order +a, -a, +b, -b, as RefinementResult::sides.
int SideIndex(bool along_a, double sign) { return (along_a ? 0 : 2) + (sign > 0.0 ? 0 : 1); }

// Fills *out (its vectors cleared first: a caller that keeps it keeps their
// capacity, and a refinement then allocates nothing).
void CollectFacePoints(const DepthImage& depth, const FaceFrame& f, double margin, double plane_tol,
                       FacePoints* out_points) {
  FacePoints& out = *out_points;
  out.interior = 0;
  out.sum.setZero();
  out.sum_outer.setZero();
  for (auto* lists : {&out.on_plane, &out.front, &out.grid}) {
    for (std::vector<FacePoint>& l : *lists) l.clear();
  }
  const CameraIntrinsics& k = depth.camera;
  std::vector<Eigen::Vector3d> outline;
  for (double sa : {-1.0, 1.0}) {
    for (double sb : {-1.0, 1.0}) {
      outline.push_back(f.c + sa * (f.half_a + margin) * f.a + sb * (f.half_b + margin) * f.b);
    }
  }
  const std::optional<PixelRect> rect = ProjectedRect(k, outline);
  if (!rect) return;
  const int ua = rect->u0, ub = rect->u1, va = rect->v0, vb = rect->v1;
  // The bands' inner edges, a hair inside so that each reader's own test
  // (which may round the other way) sees every point it would have seen.
  const double band_a = f.half_a - margin - 1e-9, band_b = f.half_b - margin - 1e-9;
  auto to_sides = [&](const FacePoint& q, std::array<std::vector<FacePoint>, 4>& sides) {
    if (q.a >= band_a) sides[0].push_back(q);
    if (-q.a >= band_a) sides[1].push_back(q);
    if (q.b >= band_b) sides[2].push_back(q);
    if (-q.b >= band_b) sides[3].push_back(q);
  };
  const double inside_a = f.half_a - 0.01, inside_b = f.half_b - 0.01;
  // Per pixel ray r = (x_u, y_v, 1), the face coordinates are linear in r:
  // a measured point z r has a = z (a.r) - a.c (and b, n alike), and the ray
  // meets the plane at s r with s = (n.c) / (n.r). The dot products with r
  // are a per-column term plus a per-row one, so a pixel costs a few
  // multiplications and one division.
  const double a_c = f.a.dot(f.c), b_c = f.b.dot(f.c), n_c = f.n.dot(f.c);
  std::vector<double> a_x(ub - ua + 1), b_x(ub - ua + 1), n_x(ub - ua + 1);
  for (int u = ua; u <= ub; ++u) {
    const double x = PixelRay(k, u, 0).x();
    a_x[u - ua] = f.a.x() * x;
    b_x[u - ua] = f.b.x() * x;
    n_x[u - ua] = f.n.x() * x;
  }
  const double lim_a = f.half_a + margin, lim_b = f.half_b + margin;
  const double in_a = f.half_a - margin, in_b = f.half_b - margin;
  // The grid is kept only near the sides: pixels well inside the image of
  // the inner rectangle (a pixel to spare) need no ray-plane intersection.
  std::array<Eigen::Vector2d, 4> inner;
  bool has_inner = in_a > 0.0 && in_b > 0.0;
  const double ia[4] = {-1.0, 1.0, 1.0, -1.0}, ib[4] = {-1.0, -1.0, 1.0, 1.0};
  for (int c = 0; c < 4 && has_inner; ++c) {
    const Eigen::Vector3d p = f.c + ia[c] * in_a * f.a + ib[c] * in_b * f.b;
    has_inner = p.z() > 0.05;
    inner[c] = has_inner ? Project(k, p) : Eigen::Vector2d::Zero();
  }
  for (int v = va; v <= vb; ++v) {
    const double y = PixelRay(k, 0, v).y();
    const double a_row = f.a.y() * y + f.a.z(), b_row = f.b.y() * y + f.b.z(),
                 n_row = f.n.y() * y + f.n.z();
    const float* zrow = &depth.z[static_cast<size_t>(v) * k.width];
    double skip0 = 0.0, skip1 = 0.0;  // (skip0, skip1): no grid
    if (has_inner && QuadRowSpan(inner, v, &skip0, &skip1)) {
      skip0 += 1.0;
      skip1 -= 1.0;
    }
    double sa = 0, sb = 0, sn = 0, saa = 0, sab = 0, san = 0, sbb = 0, sbn = 0, snn = 0;
    // The ray-plane grid near the sides (pixels outside (skip0, skip1)).
    auto grid = [&](int u, double a_r, double b_r, double n_r) {
      if (std::abs(n_r) <= 1e-6) return;
      const double t = n_c / n_r;
      const double qa = t * a_r - a_c, qb = t * b_r - b_c;
      if (std::abs(qa) <= lim_a && std::abs(qb) <= lim_b &&
          (std::abs(qa) > in_a || std::abs(qb) > in_b)) {
        const float z = zrow[u];
        const double off = z * n_r - n_c;  // NaN where no return
        const bool hit = !std::isnan(z) && std::abs(off) <= plane_tol;
        const double n = hit                ? grid_return::kOnPlane
                         : off < -plane_tol ? grid_return::kBehind
                         : off > plane_tol  ? grid_return::kInFront
                                            : grid_return::kNothing;
        to_sides(FacePoint{qa, qb, n}, out.grid);
      }
    };
    // The measured point, every pixel.
    auto measured = [&](int u, double a_r, double b_r, double n_r) {
      const float z = zrow[u];
      if (std::isnan(z)) return;
      const FacePoint q{z * a_r - a_c, z * b_r - b_c, z * n_r - n_c};
      if (std::abs(q.a) > lim_a || std::abs(q.b) > lim_b) return;
      if (q.n > plane_tol) {
        to_sides(q, out.front);
        return;
      }
      if (q.n < -plane_tol) return;
      if (!(std::abs(q.a) > inside_a || std::abs(q.b) > inside_b)) {
        ++out.interior;
        sa += q.a;
        sb += q.b;
        sn += q.n;
        saa += q.a * q.a;
        sab += q.a * q.b;
        san += q.a * q.n;
        sbb += q.b * q.b;
        sbn += q.b * q.n;
        snn += q.n * q.n;
      }
      to_sides(q, out.on_plane);
    };
    // Three runs of the row, in order (each list keeps pixel order): with
    // the grid, without it (the pixels strictly inside (skip0, skip1)),
    // with it. The split only keeps the middle run's loop small.
    const int mid0 = static_cast<int>(std::floor(std::clamp(skip0, ua - 1.0, ub + 1.0))) + 1;
    const int mid1 = static_cast<int>(std::ceil(std::clamp(skip1, ua - 1.0, ub + 1.0))) - 1;
    const int left_end = mid0 <= mid1 ? std::min(ub, mid0 - 1) : ub;
    // The pixel's ray terms (a.r, b.r, n.r), shared by both readers.
    auto both = [&](int u) {
      const double a_r = a_x[u - ua] + a_row, b_r = b_x[u - ua] + b_row, n_r = n_x[u - ua] + n_row;
      grid(u, a_r, b_r, n_r);
      measured(u, a_r, b_r, n_r);
    };
    for (int u = ua; u <= left_end; ++u) both(u);
    // The middle run without branches on the data: a point in no band
    // only adds to the interior's sums (nothing when it is not interior, a
    // no-return's NaN failing every test), in the same order; one in a
    // band takes the general path.
    auto middle = [&](int u) {
      const double a_r = a_x[u - ua] + a_row, b_r = b_x[u - ua] + b_row, n_r = n_x[u - ua] + n_row;
      const float z = zrow[u];
      const double qa = z * a_r - a_c, qb = z * b_r - b_c, qn = z * n_r - n_c;
      if (std::abs(qa) >= band_a || std::abs(qb) >= band_b) [[unlikely]] {
        measured(u, a_r, b_r, n_r);
        return;
      }
      const bool in =
          (std::abs(qn) <= plane_tol) & (std::abs(qa) <= inside_a) & (std::abs(qb) <= inside_b);
      const double ma = in ? qa : 0.0, mb = in ? qb : 0.0, mn = in ? qn : 0.0;
      out.interior += in;
      sa += ma;
      sb += mb;
      sn += mn;
      saa += ma * ma;
      sab += ma * mb;
      san += ma * mn;
      sbb += mb * mb;
      sbn += mb * mn;
      snn += mn * mn;
    };
    if (mid0 <= mid1) {
      for (int u = std::max(ua, mid0); u <= std::min(ub, mid1); ++u) middle(u);
      for (int u = std::max(ua, mid1 + 1); u <= ub; ++u) both(u);
    }
    out.sum += Eigen::Vector3d(sa, sb, sn);
    out.sum_outer += (Eigen::Matrix3d() << saa, sab, san, sab, sbb, sbn, san, sbn, snn).finished();
  }
}

// One side of the face: where it ends along `sign * a` (or b), and its turn.
struct SideMeasure {
  SideKind kind = SideKind::kUnknown;
  double position = 0.0;  // along the side's normal axis, face coordinates
  double slope = 0.0;     // d(position)/d(along), turn of the side (free sides)
  // The points on the plane just inside the side (the band's inner half).
  int inner = 0;
  // kSeam only: found past the symmetric search window, in its outward
  // extension (see OutwardSeamsNeedEverySide).
  bool outward_seam = false;
  // kUnknown only: enough of the pixels just inside the side see behind the
  // plane (RefinementOptions::seen_through_share): the face ends before it.
  bool seen_through = false;
  // kFree only: found free by RefinementOptions::side_ends_share along
  // less than side_ends_alone_share of the side (PartlyEndedNeedsTwoMore).
  bool partly_ended = false;
  // kContinues only: where the face's points end within the band.
  bool rim = false;
  double rim_position = 0.0, rim_slope = 0.0;
  // kSeam only: the seam's turn, from where each half of the side has it.
  std::optional<double> seam_slope;
  bool measured() const { return kind == SideKind::kFree || kind == SideKind::kSeam; }
};

// Sorts values whose key lies in [lo, hi) (clamped) by bucketing on the key
// and sorting each small bucket: the same order as std::sort in linear
// time (the buckets are monotonic in the key).
template <typename T, typename Key>
void BucketSort(std::vector<T>* values, double lo, double hi, Key key) {
  const size_t n = values->size();
  if (n < 64) {
    std::sort(values->begin(), values->end());
    return;
  }
  const size_t buckets = n / 2;
  const double scale = static_cast<double>(buckets) / (hi - lo);
  auto bucket_of = [&](const T& x) {
    const double b = (key(x) - lo) * scale;
    return b <= 0.0 ? size_t{0} : std::min(buckets - 1, static_cast<size_t>(b));
  };
  // Scratch kept per thread (a refinement sorts a dozen bands).
  thread_local std::vector<size_t> start, next;
  thread_local std::vector<T> out;
  start.assign(buckets + 1, 0);
  for (const T& x : *values) ++start[bucket_of(x) + 1];
  for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  out.resize(n);
  next.assign(start.begin(), start.end() - 1);
  for (const T& x : *values) out[next[bucket_of(x)]++] = x;
  // Each bucket holds a few values: an insertion sort in place (a call to
  // std::sort per bucket cost more than the sorting). Values equal under <
  // may come out in another order than std::sort's; they are equal in every
  // field the readers sum.
  for (size_t b = 0; b < buckets; ++b) {
    for (size_t i = start[b] + 1; i < start[b + 1]; ++i) {
      T x = out[i];
      size_t j = i;
      for (; j > start[b] && x < out[j - 1]; --j) out[j] = out[j - 1];
      out[j] = x;
    }
  }
  values->swap(out);
}

// The seam test over the points of one stretch of a side: strength(c) > 0
// where a seam shows at offset c. Built once for the whole side, sorted;
// a stretch (along in [along_lo, along_hi)) is a filtered copy, which keeps
// the order, so it needs no sort of its own.
class SeamScan {
 public:
  SeamScan(const std::vector<FacePoint>& pts, const std::vector<FacePoint>& grid, bool along_a,
           double sign, double half, double half_other, double pixel_m, double seam_depth_m,
           const RefinementOptions& o)
      : o_(o), depth_(seam_depth_m) {
    const double reach = o.side_band_m;
    auto band = [&](const FacePoint& p, double* across, double* along) {
      *across = sign * (along_a ? p.a : p.b) - half;
      *along = along_a ? p.b : p.a;
      return std::abs(*along) <= half_other - reach && std::abs(*across) < reach;
    };
    std::vector<Row> rows;
    rows.reserve(pts.size());
    expected_.reserve(grid.size());
    for (const FacePoint& p : pts) {
      double across, along;
      if (band(p, &across, &along)) rows.push_back({across, p.n, along});
    }
    for (const FacePoint& p : grid) {  // where pixels meet the plane, same band
      double across, along;
      if (band(p, &across, &along))
        expected_.push_back({across, along, p.n == grid_return::kOnPlane ? 1.0 : 0.0});
    }
    BucketSort(&expected_, -reach, reach, [](const Pixel& e) { return e.across; });
    BucketSort(&rows, -reach, reach, [](const Row& r) { return r.across; });
    rows_ = std::move(rows);
    Index();
    w_ = std::max(0.003, 2.5 * pixel_m);  // centre window width
    f0_ = w_ / 2 + pixel_m;               // flanks
    f1_ = w_ / 2 + 6 * pixel_m;
    spread_ = pixel_m / 2;
  }

  // The points of this side with along in [lo, hi).
  SeamScan Stretch(double lo, double hi) const {
    SeamScan part(o_, depth_);
    part.rows_.reserve(rows_.size());
    part.expected_.reserve(expected_.size());
    for (const Row& r : rows_) {
      if (r.along >= lo && r.along < hi) part.rows_.push_back(r);
    }
    for (const auto& e : expected_) {
      if (e.along >= lo && e.along < hi) part.expected_.push_back(e);
    }
    part.Index();
    part.w_ = w_;
    part.f0_ = f0_;
    part.f1_ = f1_;
    part.spread_ = spread_;
    return part;
  }

  size_t points() const { return points_.size(); }
  size_t expected() const { return grid_.size(); }

  // How far past its threshold the strongest test is at offset c (<= 0: no
  // seam there); nullopt when too few points to say.
  std::optional<double> Strength(double c) const {
    const auto [nc, sc] = Window(c - w_ / 2, c + w_ / 2);
    const auto [nl, sl] = Window(c - f1_, c - f0_);
    const auto [nr, sr] = Window(c + f0_, c + f1_);
    // The pixels whose ray meets the plane in each window (what a fully seen
    // face would give), and how many of them returned a point on it.
    const auto [pc, hc] = PixelsIn(c - w_ / 2, c + w_ / 2);
    const auto [pl, hl] = PixelsIn(c - f1_, c - f0_);
    const auto [pr, hr] = PixelsIn(c + f0_, c + f1_);
    const double ec = pc, ef = pl + pr;
    if (nl < 10 || nr < 10 || ec < 5 || ef < 10) return std::nullopt;
    // Share of the pixels that should see the plane and do, at the centre
    // against the flanks: the pixel grid's own pattern cancels out.
    const double density_ratio = (nc / ec) / ((nl + nr) / ef);
    const double groove =
        nc >= 5 ? (sl + sr) / (nl + nr) - sc / nc : 0.0;  // how much lower the centre is
    // Strength: how far past its threshold each test is; a weaker dip in
    // density counts when a groove half as deep as the threshold backs it.
    const double density_strength = (o_.max_seam_density - density_ratio) / o_.max_seam_density;
    // A groove alone must be deeper than the face is rough (depth_); one
    // that comes with a dip in density (missing returns, which a Kinect's
    // disparity stripes do not make) needs only half of min_seam_depth_m.
    const double groove_strength = (groove - depth_) / depth_;
    const double joint_strength =
        std::min((o_.weak_seam_density - density_ratio) / o_.weak_seam_density,
                 (groove - 0.5 * o_.min_seam_depth_m) / o_.min_seam_depth_m);
    // A sparse line of missing returns (a gap finer than a pixel): the
    // missing share above the flanks', and how unlikely that excess is at
    // the flanks' rate (a floor of one in 200 keeps a spotless face from
    // making every stray miss significant).
    double sparse_strength = -std::numeric_limits<double>::infinity();
    if (o_.sparse_seam_missing > 0.0 && o_.sparse_seam_sigma > 0.0) {
      // Counted on the pixels, not the points: a groove displaces points
      // sideways (a deeper point on a slanted ray lands further out) and
      // thins them on one flank without any return missing.
      const double missing_c = 1.0 - hc / pc, missing_f = 1.0 - (hl + hr) / ef;
      const double excess = (pc - hc) - pc * missing_f;
      const double sigma = std::sqrt(pc * std::max(missing_f, 0.005) + 1.0);
      sparse_strength =
          std::min((missing_c - missing_f - o_.sparse_seam_missing) / o_.sparse_seam_missing,
                   (excess / sigma - o_.sparse_seam_sigma) / o_.sparse_seam_sigma);
    }
    return std::max({density_strength, groove_strength, joint_strength, sparse_strength});
  }

 private:
  struct Row {
    double across, height, along;  // across: offset from the side
    bool operator<(const Row& r) const {
      return across != r.across ? across < r.across : height < r.height;
    }
  };
  SeamScan(const RefinementOptions& o, double seam_depth_m) : o_(o), depth_(seam_depth_m) {}

  // Sorted positions x with prefix sums of 1, x, y and x y: the count and
  // y-sum of the points in a window [lo, hi) when each point is spread
  // evenly over [x - spread, x + spread] (a pixel's footprint). A side that
  // runs along a pixel row or column meets the pixel grid in rows a pixel
  // apart; counted as points, a window's share of them jumps by a third as
  // its ends cross a row, and where the measured points lie jittered off
  // the rows (lateral noise) but the ray-plane grid does not, that jump
  // reads as a dip in density. Spread alike, both count smoothly.
  class SpreadSums {
   public:
    // From values sorted by their x (xy(v) gives (x, y)).
    template <typename T, typename XY>
    void Build(const std::vector<T>& values, XY xy) {
      const size_t n = values.size();
      x_.resize(n);
      sum_.resize(n + 1);
      sum_[0] = Sums{};
      for (size_t i = 0; i < n; ++i) {
        const auto [x, y] = xy(values[i]);
        x_[i] = x;
        sum_[i + 1] = {sum_[i].x + x, sum_[i].y + y, sum_[i].xy + x * y};
      }
      // Where each of n / 4 equal cells of x's range starts (CellOf).
      cells_ = n >= 16 && x_.back() > x_.front() ? n / 4 : 0;
      cell_start_.assign(cells_ + 1, 0);
      if (cells_ == 0) return;
      x0_ = x_.front();
      scale_ = static_cast<double>(cells_) / (x_.back() - x_.front());
      for (double x : x_) ++cell_start_[CellOf(x) + 1];
      for (size_t c = 0; c < cells_; ++c) cell_start_[c + 1] += cell_start_[c];
    }
    size_t size() const { return x_.size(); }
    // (weighted count, weighted y-sum) over [lo, hi).
    std::pair<double, double> Window(double lo, double hi, double spread) const {
      const double h = std::min(spread, 0.5 * (hi - lo));
      if (h <= 0.0) {
        const size_t a = Index(lo), b = Index(hi);
        return {static_cast<double>(b - a), sum_[b].y - sum_[a].y};
      }
      const size_t i0 = Index(lo - h), i1 = Index(lo + h), i2 = Index(hi - h), i3 = Index(hi + h);
      const double n01 = static_cast<double>(i1 - i0), n23 = static_cast<double>(i3 - i2);
      const Sums s01 = Diff(i0, i1), s12 = Diff(i1, i2), s23 = Diff(i2, i3);
      // Points near lo weigh (x - lo + h) / 2h, near hi (hi + h - x) / 2h.
      const double count = static_cast<double>(i2 - i1) + (s01.x - n01 * (lo - h)) / (2 * h) +
                           (n23 * (hi + h) - s23.x) / (2 * h);
      const double ysum =
          s12.y + (s01.xy - (lo - h) * s01.y) / (2 * h) + ((hi + h) * s23.y - s23.xy) / (2 * h);
      return {count, ysum};
    }

   private:
    struct Sums {
      double x = 0.0, y = 0.0, xy = 0.0;
    };
    // The cell of x's range that v falls in, clamped: monotonic in v, so
    // every point of a lower cell lies below v and every point of a higher
    // one above it, and the first point >= v lies within v's cell or at
    // the next cell's start.
    size_t CellOf(double v) const {
      const double t = (v - x0_) * scale_;
      return t <= 0.0 ? 0 : std::min(cells_ - 1, static_cast<size_t>(t));
    }
    // The first point >= v (std::lower_bound), searched within v's cell.
    size_t Index(double v) const {
      if (cells_ == 0) return std::lower_bound(x_.begin(), x_.end(), v) - x_.begin();
      const size_t c = CellOf(v);
      return std::lower_bound(x_.begin() + cell_start_[c], x_.begin() + cell_start_[c + 1], v) -
             x_.begin();
    }
    Sums Diff(size_t a, size_t b) const {
      return {sum_[b].x - sum_[a].x, sum_[b].y - sum_[a].y, sum_[b].xy - sum_[a].xy};
    }
    std::vector<double> x_;
    std::vector<Sums> sum_;
    size_t cells_ = 0;
    double x0_ = 0.0, scale_ = 0.0;
    std::vector<size_t> cell_start_;
  };

  void Index() {
    points_.Build(rows_, [](const Row& r) { return std::pair{r.across, r.height}; });
    grid_.Build(expected_, [](const Pixel& e) { return std::pair{e.across, e.hit}; });
  }
  // Count and height sum of points with across in [lo, hi).
  std::pair<double, double> Window(double lo, double hi) const {
    return points_.Window(lo, hi, spread_);
  }
  // Pixels whose ray meets the plane in [lo, hi), and how many of them
  // returned a point on it.
  std::pair<double, double> PixelsIn(double lo, double hi) const {
    return grid_.Window(lo, hi, spread_);
  }

  const RefinementOptions& o_;
  double depth_;  // least groove depth for a seam (FacePoints::seam_depth_m)
  std::vector<Row> rows_;
  struct Pixel {
    double across, along, hit;  // hit: 1 with a return on the plane, else 0
    bool operator<(const Pixel& p) const {
      return across != p.across ? across < p.across : along < p.along;
    }
  };
  std::vector<Pixel> expected_;
  SpreadSums points_, grid_;
  double w_ = 0.0, f0_ = 0.0, f1_ = 0.0;
  double spread_ = 0.0;  // half a pixel's footprint on the face
};

// Looks for the seam two touching boxes leave between coplanar faces. A
// wide enough gap shows as a line of missing returns (a dip in the density
// of points on the plane); a fine one only as a shallow groove from the
// rounded edges (a dip in their mean height). Both are measured in a window
// sliding across the side, against flanks a few pixels away, and only within
// seam_search_m of the hypothesised side: the Kinect's depth noise is
// spatially correlated, and a dip searched for everywhere is often noise.
// Returns the seam's position (outward coordinate) or nothing.
std::optional<double> FindSeam(const std::vector<FacePoint>& pts,
                               const std::vector<FacePoint>& grid, bool along_a, double sign,
                               double half, double half_other, double pixel_m, double seam_depth_m,
                               const RefinementOptions& o, std::optional<double>* slope) {
  constexpr double kAll = std::numeric_limits<double>::infinity();
  const SeamScan whole(pts, grid, along_a, sign, half, half_other, pixel_m, seam_depth_m, o);
  if (whole.points() < 50 || whole.expected() < 50) return std::nullopt;
  std::optional<double> best;
  double best_strength = 0.0;
  // Further out than in: a face placed by a free side that reads long (a
  // stereo camera's fattened edge, a bulge) puts the seam side short of
  // the seam (RefinementOptions::seam_search_outward_m).
  const double lo = -o.seam_search_m, hi = o.seam_search_m + o.seam_search_outward_m;
  for (double c = lo; c <= hi + 1e-9; c += 0.001) {
    const std::optional<double> strength = whole.Strength(c);
    if (strength && *strength > 0.0 && *strength > best_strength) {
      best_strength = *strength;
      best = c;
    }
  }
  // A dip at the end of the search range is the flank of something
  // further away, not a seam here.
  if (!best || *best < lo + 0.0015 || *best > hi - 0.0015) return std::nullopt;
  // A seam runs the whole side: each half of it shows one near the same
  // offset (within a millimetre), if only a weak one. A cluster of missing
  // returns in one place (Kinect speckle) makes a dip in the whole side's
  // sums but not in both halves.
  // Each half's scan, made once for both uses below.
  std::array<std::optional<SeamScan>, 2> halves;
  auto half_scan = [&](int k) -> const SeamScan& {
    if (!halves[k])
      halves[k].emplace(k == 0 ? whole.Stretch(-kAll, 0.0) : whole.Stretch(0.0, kAll));
    return *halves[k];
  };
  if (o.seam_halves_min_strength > -1.0) {
    for (int k = 0; k < 2; ++k) {
      const SeamScan& part = half_scan(k);
      double strongest = -kAll;
      for (double c = *best - 0.001; c <= *best + 0.001 + 1e-9; c += 0.001) {
        if (const std::optional<double> st = part.Strength(c)) strongest = std::max(strongest, *st);
      }
      if (std::isfinite(strongest) && strongest <= o.seam_halves_min_strength) return std::nullopt;
    }
  }
  // Where each half of the side has its seam (searched 4 mm either way of
  // the whole side's, every half millimetre): the seam's turn.
  const double reach = half_other - o.side_band_m;  // the side's stretch, either way
  if (slope != nullptr && o.seam_turn_min_length_m > 0.0 &&
      2.0 * reach >= o.seam_turn_min_length_m) {
    double at[2];
    bool found = true;
    for (int k = 0; k < 2; ++k) {
      const SeamScan& part = half_scan(k);
      double strongest = 0.0;
      std::optional<double> pos;
      for (double c = *best - 0.004; c <= *best + 0.004 + 1e-9; c += 0.0005) {
        const std::optional<double> st = part.Strength(c);
        if (st && *st > strongest) {
          strongest = *st;
          pos = c;
        }
      }
      if (!pos) found = false;
      at[k] = pos.value_or(0.0);
    }
    // The halves' centres lie reach / 2 either side of the middle.
    const double cap = std::tan(o.seam_turn_max_deg * std::numbers::pi / 180.0);
    if (found) *slope = std::clamp((at[1] - at[0]) / reach, -cap, cap);
  }
  return half + *best;
}

SideMeasure MeasureSide(const FacePoints& face, bool along_a, double sign, double half,
                        double half_other, double pixel_m, const RefinementOptions& o) {
  const int side = SideIndex(along_a, sign);
  const std::vector<FacePoint>& pts = face.on_plane[side];
  const std::vector<FacePoint>& front = face.front[side];
  const std::vector<FacePoint>& grid = face.grid[side];
  const double band = o.side_band_m;
  int inner = 0, outer = 0;
  const double bin = 0.01;
  const int nbins = std::max(1, static_cast<int>(2.0 * (half_other - band) / bin));
  std::vector<double> best(nbins, -std::numeric_limits<double>::max());
  for (const FacePoint& p : pts) {
    const double across = sign * (along_a ? p.a : p.b);  // outward coordinate
    const double along = along_a ? p.b : p.a;
    if (std::abs(along) > half_other - band) continue;
    if (across > half + 0.005 && across <= half + band) ++outer;
    if (across >= half - band && across < half - 0.005) ++inner;
    if (across >= half - band && across <= half + band) {
      const int k = std::clamp(static_cast<int>((along + half_other - band) / bin), 0, nbins - 1);
      best[k] = std::max(best[k], across);
    }
  }
  SideMeasure m;
  if (inner < 10) {  // hidden or cut: no say, unless seen through
    // The pixels just inside the side: where nothing in front hides the
    // plane, do they see behind it?
    int pixels = 0, behind = 0, hidden = 0;
    for (const FacePoint& g : grid) {
      const double across = sign * (along_a ? g.a : g.b);
      const double along = along_a ? g.b : g.a;
      if (std::abs(along) > half_other - band || across < half - band || across >= half - 0.005) {
        continue;
      }
      ++pixels;
      behind += g.n == grid_return::kBehind;
      hidden += g.n == grid_return::kInFront;
    }
    m.seen_through = o.seen_through_share > 0.0 && behind >= 10 &&
                     behind >= o.seen_through_share * (pixels - hidden);
    return m;
  }
  m.inner = inner;
  // Something in front of the plane just past the side: the face may go on
  // underneath it, so the side is not where the face ends.
  int in_front = 0;
  for (const FacePoint& p : front) {
    const double across = sign * (along_a ? p.a : p.b);
    const double along = along_a ? p.b : p.a;
    in_front +=
        std::abs(along) <= half_other - band && across > half + 0.005 && across <= half + band;
  }
  if (in_front > o.free_side_ratio * inner && in_front > outer) {
    m.kind = SideKind::kOccluded;
    return m;
  }
  // Outermost point per bin, then a robust line through them: where the
  // face ends (false when too few bins have a point), from the bins whose
  // outermost point lies no further out than `up_to`.
  auto measure_end = [&](SideMeasure* out, double up_to = 1.0) {
    std::vector<std::pair<double, double>> ends;  // (along, across)
    for (int k = 0; k < nbins; ++k) {
      if (best[k] > -1.0 && best[k] <= up_to) {
        ends.emplace_back(-half_other + band + (k + 0.5) * bin, best[k]);
      }
    }
    if (static_cast<int>(ends.size()) < std::max(3, nbins / 3)) return false;
    std::vector<double> across;
    across.reserve(ends.size());
    for (auto& e : ends) across.push_back(e.second);
    out->position = Median(across);
    // Slope by the median of pairwise slopes (Theil-Sen) over bins far apart.
    std::vector<double> slopes;
    for (size_t i = 0; i < ends.size(); ++i) {
      for (size_t j = i + 1; j < ends.size(); ++j) {
        const double dl = ends[j].first - ends[i].first;
        if (dl > 0.03) slopes.push_back((ends[j].second - ends[i].second) / dl);
      }
    }
    out->slope = slopes.empty() ? 0.0 : Median(slopes);
    return true;
  };
  // Something flat past only part of the side, the face ending at the side
  // along the rest (RefinementOptions::side_ends_share): the side is free
  // where the face ends, measured along that rest.
  if (outer > o.free_side_ratio * inner && o.side_ends_share > 0.0) {
    const int ends = static_cast<int>(std::count_if(
        best.begin(), best.end(), [&](double b) { return b > -1.0 && b <= half + 0.005; }));
    if (ends >= o.side_ends_share * nbins && measure_end(&m, half + 0.005)) {
      m.kind = SideKind::kFree;
      m.partly_ended = ends < o.side_ends_alone_share * nbins;
      return m;
    }
  }
  if (outer > o.free_side_ratio * inner) {
    // The face continues past the side: a seam to a touching box, or the
    // hypothesis is too small for this face.
    // ... or only its rim does, ending within the band: where it ends, for
    // RimAsFree to decide. Measured for a seam too: one the colour image
    // or the outward search's rule drops again (ConfirmSeamInColour,
    // OutwardSeamsNeedEverySide) leaves a side that runs on, and a stereo
    // camera's fattened rim reads as a groove just past its edge.
    auto rim = [&] {
      if (!o.rim_ends_side) return;
      SideMeasure end;
      if (measure_end(&end)) {
        m.rim_position = end.position;
        m.rim_slope = end.slope;
        m.rim = true;
      }
    };
    if (std::optional<double> seam = FindSeam(pts, grid, along_a, sign, half, half_other, pixel_m,
                                              face.seam_depth_m, o, &m.seam_slope)) {
      m.kind = SideKind::kSeam;
      m.position = *seam;
      m.outward_seam = *seam - half > o.seam_search_m - 0.0015;
      rim();
    } else {
      m.kind = SideKind::kContinues;
      rim();
    }
    return m;
  }
  if (!measure_end(&m)) return m;
  m.kind = SideKind::kFree;
  return m;
}

// A side free where the face ends along only part of it (SideMeasure::
// partly_ended) stays free only when at least two of the face's three other
// sides are measured; otherwise the face runs on there: two bricks lying in
// an L with level tops hold a reading across both, turned a quarter, that
// ends along part of one side and has two sides hidden.
void PartlyEndedNeedsTwoMore(const std::array<SideMeasure*, 4>& sides) {
  for (int i = 0; i < 4; ++i) {
    if (sides[i]->kind != SideKind::kFree || !sides[i]->partly_ended) continue;
    int unmeasured = 0;
    for (int j = 0; j < 4; ++j) unmeasured += j != i && !sides[j]->measured();
    if (unmeasured > 1) {
      sides[i]->kind = SideKind::kContinues;
      sides[i]->partly_ended = false;
    }
  }
}

// No side of the face hidden under something or cut by the image's edge.
bool EverySideSeen(const std::array<SideMeasure*, 4>& sides) {
  return std::none_of(sides.begin(), sides.end(), [](const SideMeasure* m) {
    return m->kind == SideKind::kUnknown || m->kind == SideKind::kOccluded;
  });
}

// A seam found only in the outward extension of the search is kept when
// every side of the face is measured (none hidden or cut): a face pinned
// by such a seam and a side out of sight was, on the generated pallets, a
// box's end face carved out of a longer top by Kinect noise.
void OutwardSeamsNeedEverySide(const std::array<SideMeasure*, 4>& sides) {
  if (EverySideSeen(sides)) return;
  for (SideMeasure* m : sides) {
    if (m->kind == SideKind::kSeam && m->outward_seam) m->kind = SideKind::kContinues;
  }
}

// Points on the face's plane (within twice its tolerance: a plane fitted
// to a small, noisy face may be off by degrees, which a band further out
// magnifies) one band past `side` (margin to twice it out, clear of the
// corners), over the points just inside the side: whether a face that runs
// past the side goes on, or ends within the band.
double FurtherShare(const DepthImage& depth, const FaceFrame& f, int side, int inner, double margin,
                    double plane_tol) {
  if (inner <= 0) return 0.0;
  const bool along_a = side < 2;
  const double sign = side % 2 == 0 ? 1.0 : -1.0;
  const Eigen::Vector3d across = sign * (along_a ? f.a : f.b), along = along_a ? f.b : f.a;
  const double half = along_a ? f.half_a : f.half_b;
  const double reach = (along_a ? f.half_b : f.half_a) - margin;
  if (reach <= 0.0) return 0.0;
  std::vector<Eigen::Vector3d> strip;
  for (double out : {half + margin, half + 2.0 * margin}) {
    for (double s : {-reach, reach}) strip.push_back(f.c + out * across + s * along);
  }
  const std::optional<PixelRect> r = ProjectedRect(depth.camera, strip);
  if (!r) return 0.0;
  // Pixels more all round: a point off the plane (up to twice its
  // tolerance) lands beside the strip's image.
  const CameraIntrinsics& k = depth.camera;
  const int slack =
      1 + static_cast<int>(std::ceil(2.0 * plane_tol * k.fx / std::max(0.1, f.c.z())));
  int further = 0;
  const int u0 = std::max(0, r->u0 - slack), u1 = std::min(k.width - 1, r->u1 + slack);
  // The rays' x per column, computed once (PixelRay's own values).
  thread_local std::vector<double> ray_x;
  ray_x.resize(std::max(0, u1 - u0 + 1));
  for (int u = u0; u <= u1; ++u) ray_x[u - u0] = PixelRay(k, u, 0).x();
  for (int v = std::max(0, r->v0 - slack); v <= std::min(k.height - 1, r->v1 + slack); ++v) {
    const double ray_y = PixelRay(k, 0, v).y();
    for (int u = u0; u <= u1; ++u) {
      const float z = depth.at(u, v);
      if (std::isnan(z)) continue;
      const Eigen::Vector3d d =
          static_cast<double>(z) * Eigen::Vector3d(ray_x[u - u0], ray_y, 1.0) - f.c;
      if (std::abs(d.dot(f.n)) > 2.0 * plane_tol) continue;
      const double out = d.dot(across);
      further +=
          out > half + margin && out <= half + 2.0 * margin && std::abs(d.dot(along)) <= reach;
    }
  }
  return static_cast<double>(further) / inner;
}

// A face whose rim spreads past one side (a bulging carton; an active stereo
// camera's fattened edges and smoothing; noise at a crease seen obliquely)
// runs on past that side by a centimetre or so and then ends: the side is
// free where the face ends, when that is the only side in doubt: its
// opposite side free, and every side of the face measured (a side hidden or
// cut would leave the face's true size open), or (rim_beside_occluded) its
// opposite side occluded and the other axis measured on both sides: the
// face's size across is then the box's, from the rim. `further(i)` is side i's
// FurtherShare (read only for the few faces that get that far).
template <typename Further>
void RimAsFree(const std::array<SideMeasure*, 4>& sides, double half_a, double half_b,
               const RefinementOptions& o, const Further& further) {
  // With rim_beside_occluded, one side may be occluded: the rim's opposite.
  int occluded = -1;
  for (int i = 0; i < 4; ++i) {
    if (sides[i]->kind == SideKind::kUnknown) return;
    if (sides[i]->kind != SideKind::kOccluded) continue;
    if (occluded >= 0 || !o.rim_beside_occluded) return;
    occluded = i;
  }
  auto candidate = [&](int i) {
    return sides[i]->kind == SideKind::kContinues && sides[i]->rim &&
           (occluded < 0 || occluded == (i ^ 1));
  };
  // The face so measured is the box's size on both axes: across the rim
  // from rim_extent_tolerance_m short to twice it long (the rim adds to
  // it), along it within the tolerance when both its sides are free (a face
  // a rim too big is also what a box of another size shows). The opposite
  // side must end the face (free, and below: for good).
  auto fits = [&](int rim) {
    const SideMeasure& m = *sides[rim];
    const SideMeasure& opposite = *sides[rim ^ 1];
    const double half = rim < 2 ? half_a : half_b, other_half = rim < 2 ? half_b : half_a;
    const SideMeasure& o1 = *sides[rim < 2 ? 2 : 0];
    const SideMeasure& o2 = *sides[rim < 2 ? 3 : 1];
    if (opposite.kind == SideKind::kOccluded) {
      // The face may go on under what stands there: its extent across is
      // open, so the other axis must be pinned on both sides.
      if (!o1.measured() || !o2.measured()) return false;
      return !(o1.kind == SideKind::kFree && o2.kind == SideKind::kFree &&
               std::abs(o1.position + o2.position - 2.0 * other_half) > o.rim_extent_tolerance_m);
    }
    const double over = m.rim_position + opposite.position - 2.0 * half;
    return opposite.kind == SideKind::kFree && over >= -o.rim_extent_tolerance_m &&
           over <= 2.0 * o.rim_extent_tolerance_m &&
           !(o1.kind == SideKind::kFree && o2.kind == SideKind::kFree &&
             std::abs(o1.position + o2.position - 2.0 * other_half) > o.rim_extent_tolerance_m);
  };
  // The strips past the sides (further) are read only where a rim could
  // pass: on a layer of touching boxes every side runs on and none is free.
  bool any_fits = false;
  for (int i = 0; i < 4; ++i) any_fits = any_fits || (candidate(i) && fits(i));
  if (!any_fits) return;
  // A rim: the face runs on past the side, but nothing of it a band further.
  int rims = 0, rim = -1;
  for (int i = 0; i < 4 && rims < 2; ++i) {
    if (candidate(i) && further(i) <= o.free_side_ratio) {
      ++rims;
      rim = i;
    }
  }
  if (rims != 1 || !fits(rim)) return;
  // The opposite side must end the face for good: no plane resuming past
  // it (a strip of missing returns across a face, as dark tape leaves on a
  // stereo camera, ends half of it at a free side).
  if (further(rim ^ 1) > o.free_side_ratio) return;
  SideMeasure& m = *sides[rim];
  m.kind = SideKind::kFree;
  m.position = m.rim_position;
  m.slope = m.rim_slope;
}

// The image line along a side at `position` (face coordinates along the
// side's outward normal).
SeamCue ColourLineAt(const DepthImage& depth, const FaceFrame& f, bool along_a, double sign,
                     double position, const SeamCueOptions& o) {
  const Eigen::Vector3d across = sign * (along_a ? f.a : f.b);
  const Eigen::Vector3d along = along_a ? f.b : f.a;
  const double half_other = along_a ? f.half_b : f.half_a;
  const Eigen::Vector3d mid = f.c + position * across;
  return ColourSeamAlong(depth, mid - half_other * along, mid + half_other * along, across, o);
}

// Whether the colour image shows anything about this face: its brightness
// varies by at least the seam cue's contrast over the face and a band
// around it (9 x 9 samples). Only then does a missing line along a depth
// seam say anything; a blank image is no evidence either way.
bool ColourVariesAroundFace(const DepthImage& depth, const FaceFrame& f,
                            const RefinementOptions& o) {
  float lo = 255.0f, hi = 0.0f;
  const double reach_a = f.half_a + o.side_band_m, reach_b = f.half_b + o.side_band_m;
  for (int i = 0; i <= 8; ++i) {
    for (int j = 0; j <= 8; ++j) {
      const Eigen::Vector3d p =
          f.c + (i / 4.0 - 1.0) * reach_a * f.a + (j / 4.0 - 1.0) * reach_b * f.b;
      if (p.z() <= 0.05) continue;
      const Eigen::Vector2d px = Project(depth.camera, p);
      const int u = static_cast<int>(std::lround(px.x())),
                v = static_cast<int>(std::lround(px.y()));
      if (!depth.inside(u, v)) continue;
      lo = std::min(lo, depth.grey_at(u, v));
      hi = std::max(hi, depth.grey_at(u, v));
    }
  }
  return hi - lo >= o.colour_seams.min_contrast;
}

// A depth seam without an image line along it (coverage below
// colour_confirms_seam) is noise in the depth: the face runs on there.
void ConfirmSeamInColour(const DepthImage& depth, const FaceFrame& f, bool along_a, double sign,
                         const RefinementOptions& o, SideMeasure* m) {
  if (m->kind != SideKind::kSeam) return;
  if (ColourLineAt(depth, f, along_a, sign, m->position, o.colour_seams).coverage <
      o.colour_confirms_seam) {
    m->kind = SideKind::kContinues;
  }
}

// A continuing side becomes a seam when the colour image shows a straight
// line along all of it within seam_search_m (plus the colour search) of the
// hypothesised side.
void ColourSeamSide(const DepthImage& depth, const FaceFrame& f, bool along_a, double sign,
                    const RefinementOptions& o, SideMeasure* m) {
  if (m->kind != SideKind::kContinues) return;
  const double half = along_a ? f.half_a : f.half_b;
  const SeamCue cue = ColourLineAt(depth, f, along_a, sign, half, o.colour_seams);
  if (!cue.seam || std::abs(cue.offset_m) > o.seam_search_m + 0.004) return;
  m->kind = SideKind::kSeam;
  m->position = half + cue.offset_m;
  // Along a long side, the line's turn turns the face as a depth seam's
  // does (seam_turn_min_length_m): a brick inside a pallet, bounded by
  // seams the depth does not show, otherwise keeps the turn it came with.
  const double half_other = along_a ? f.half_b : f.half_a;
  if (cue.slope && o.seam_turn_min_length_m > 0.0 &&
      2.0 * (half_other - o.side_band_m) >= o.seam_turn_min_length_m) {
    const double cap = std::tan(o.seam_turn_max_deg * std::numbers::pi / 180.0);
    m->seam_slope = std::clamp(*cue.slope, -cap, cap);
  }
}

// True when, past a side, the first surface after a run of missing returns
// lies in front of the face's plane (the gap is the shadow of something
// standing over the face), or the first surface right at the side (past the
// face's own blur) lies in front of it on two of three lines (a box of an
// upper layer, its wall or its top, standing over this one): the face may
// go on underneath, so the side is not where the face ends. Looks up to
// 8 cm out along three lines across the side.
bool ShadowedByOccluder(const DepthImage& depth, const Eigen::Vector3d& side_centre,
                        const Eigen::Vector3d& across, const Eigen::Vector3d& along,
                        double half_along, const RefinementOptions& o,
                        const Eigen::Vector3d& normal) {
  // One line only is more often a neighbour in a heap standing higher at
  // one corner than a face that goes on.
  int in_front = 0;  // lines on which something stands in front of the plane at the side
  for (double t : {-0.6, 0.0, 0.6}) {
    const Eigen::Vector3d start = side_centre + t * half_along * along;
    for (double d = 0.004; d < 0.08; d += 0.003) {
      const std::optional<double> h = HeightAt(depth, start + d * across, normal);
      if (!h) break;
      if (std::isnan(*h)) continue;
      const double height = *h;
      // Within the side's blur (mixed pixels, a side measured a few
      // millimetres short) the face itself may still show: look past it.
      if (std::abs(height) <= o.plane_tolerance_m && d <= 0.012) continue;
      if (height > o.plane_tolerance_m && d > 0.012) return true;
      in_front += height > o.plane_tolerance_m;
      break;  // a surface at or behind the plane: a real end
    }
  }
  return in_front >= 2;
}

// Where, past a free side, the face's plane goes on after a gap of
// slat_gap_min_m to slat_gap_max_m on two of three lines across the side
// (off the plane, or no return, from the side's blur on, then two samples
// on the plane again within the gap's range): the point on the plane where
// it goes on (the middle-most such line's). Something standing in front of
// the plane on a line ends that line (not one flat surface).
std::optional<Eigen::Vector3d> PlaneGoesOnPastGap(const DepthImage& depth,
                                                  const Eigen::Vector3d& side_centre,
                                                  const Eigen::Vector3d& across,
                                                  const Eigen::Vector3d& along, double half_along,
                                                  const RefinementOptions& o,
                                                  const Eigen::Vector3d& normal) {
  constexpr double kStep = 0.003, kBlur = 0.012;
  int lines = 0;
  std::optional<Eigen::Vector3d> resumes;
  for (double t : {0.0, -0.6, 0.6}) {
    const Eigen::Vector3d start = side_centre + t * half_along * along;
    int off = 0, on = 0;
    for (double d = 0.004; d <= o.slat_gap_max_m + kStep; d += kStep) {
      const std::optional<double> h = HeightAt(depth, start + d * across, normal);
      if (!h) break;
      if (*h > o.plane_tolerance_m) break;           // something in front
      if (!(std::abs(*h) <= o.plane_tolerance_m)) {  // off the plane, or no return
        ++off;
        on = 0;
        continue;
      }
      if (off < 2) {
        if (d > kBlur) break;  // the plane goes on with no gap: not a free side's
        continue;              // within the side's blur
      }
      if (++on == 2 && d - kStep >= o.slat_gap_min_m) {
        ++lines;
        if (!resumes) resumes = start + (d - kStep) * across;
        break;
      }
    }
  }
  if (lines < 2) return std::nullopt;
  return resumes;
}

// Where the face's plane ends beyond one side: marches outward from the
// side along `dir` on the plane, reading the depth image, until the measured
// surface leaves the plane for good. Returns the distance from the side to
// that end (metres), or nothing when the march leaves the image first.
std::optional<double> DistanceToPlaneEnd(const DepthImage& depth, const Eigen::Vector3d& start,
                                         const Eigen::Vector3d& dir, const Eigen::Vector3d& normal,
                                         const RefinementOptions& o) {
  constexpr double kStep = 0.004;
  constexpr int kOffPlaneToEnd = 4;  // consecutive samples off the plane (1.6 cm)
  int off = 0;
  for (double d = kStep; d < o.max_tile_march_m; d += kStep) {
    const std::optional<double> h = HeightAt(depth, start + d * dir, normal);
    if (!h) return std::nullopt;
    // Something in front hides where the plane ends.
    if (*h > o.plane_tolerance_m) return std::nullopt;
    const bool on_plane = std::abs(*h) < o.plane_tolerance_m;  // no return (NaN): off it
    off = on_plane ? 0 : off + 1;
    if (off == kOffPlaneToEnd) return d - (kOffPlaneToEnd - 0.5) * kStep;
  }
  return std::nullopt;
}

// Distances from a side to where the face's plane ends beyond it, along
// three lines across the side (a layer can be notched where boxes were
// taken); nothing when any march leaves the image.
std::optional<std::array<double, 3>> LayerRunsBeyond(
    const DepthImage& depth, const Eigen::Vector3d& side_centre, const Eigen::Vector3d& across,
    const Eigen::Vector3d& along, double half_along, const Eigen::Vector3d& normal,
    const RefinementOptions& o) {
  std::array<double, 3> runs;
  const double offsets[3] = {-0.6, 0.0, 0.6};
  for (int i = 0; i < 3; ++i) {
    const std::optional<double> d =
        DistanceToPlaneEnd(depth, side_centre + offsets[i] * half_along * along, across, normal, o);
    if (!d) return std::nullopt;
    runs[i] = *d;
  }
  return runs;
}

// How many tiles of size `tile`, laid with gaps of 0 to 2 tile_gap_m, make
// a run of `extent` metres (within `tolerance`); 0 when none do.
int TileCount(double extent, double tile, double tolerance, const RefinementOptions& o) {
  const int k = static_cast<int>(std::lround(extent / (tile + o.tile_gap_m)));
  if (k < 1) return 0;
  const double slack = extent - k * tile;  // room left for k - 1 gaps
  const bool fits = slack >= -tolerance && slack <= (k - 1) * 2.0 * o.tile_gap_m + tolerance;
  return fits ? k : 0;
}

}  // namespace

absl::Status RefinementOptions::Validate() const {
  if (absl::Status s = colour_seams.Validate(); !s.ok()) return s;
  for (absl::Status s : {
           CheckPositive("refinement.plane_tolerance_m", plane_tolerance_m, 0.2),
           CheckRange("refinement.side_band_m", side_band_m, 0.005, 0.2),
           CheckRange("refinement.free_side_ratio", free_side_ratio, 0.0, 1.0),
           CheckRange("refinement.min_seam_depth_m", min_seam_depth_m, 0.0, 0.1),
           CheckRange("refinement.max_seam_density", max_seam_density, 0.0, 1.0),
           CheckRange("refinement.weak_seam_density", weak_seam_density, 0.0, 1.0),
           CheckRange("refinement.sparse_seam_missing", sparse_seam_missing, 0.0, 1.0),
           CheckRange("refinement.sparse_seam_sigma", sparse_seam_sigma, 0.0, 100.0),
           CheckRange("refinement.seam_search_m", seam_search_m, 0.0, 0.2),
           CheckRange("refinement.seam_search_outward_m", seam_search_outward_m, 0.0, 0.2),
           CheckRange("refinement.colour_confirms_seam", colour_confirms_seam, 0.0, 1.0),
           CheckRange("refinement.seam_halves_min_strength", seam_halves_min_strength, -10.0, 1.0),
           CheckRange("refinement.tile_gap_m", tile_gap_m, 0.0, 0.2),
           CheckRange("refinement.tile_tolerance_m", tile_tolerance_m, 0.0, 0.2),
           CheckRange("refinement.max_tile_march_m", max_tile_march_m, 0.0, 100.0),
           CheckRange("refinement.rim_extent_tolerance_m", rim_extent_tolerance_m, 0.0, 0.1),
           CheckRange("refinement.side_ends_share", side_ends_share, 0.0, 1.0),
           CheckRange("refinement.side_ends_alone_share", side_ends_alone_share, 0.0, 1.0),
           CheckRange("refinement.seam_depth_per_rms", seam_depth_per_rms, 0.0, 10.0),
           CheckRange("refinement.iterations", iterations, 0, 20),
           CheckRange("refinement.end_on_flat_shift_m", end_on_flat_shift_m, 0.0, 0.05),
           CheckRange("refinement.extra_step_corner_move_m", extra_step_corner_move_m, 0.0, 0.05),
           CheckRange("refinement.seam_turn_min_length_m", seam_turn_min_length_m, 0.0, 10.0),
           CheckRange("refinement.seam_turn_max_deg", seam_turn_max_deg, 0.0, 45.0),
           CheckRange("refinement.slat_gap_min_m", slat_gap_min_m, 0.0, 0.5),
           CheckRange("refinement.slat_gap_max_m", slat_gap_max_m, 0.0, 0.5),
           CheckRange("refinement.seen_through_share", seen_through_share, 0.0, 1.0),
           CheckPositive("refinement.max_shift_m", max_shift_m),
           CheckPositive("refinement.max_turn_deg", max_turn_deg),
           CheckRange("refinement.first_step_give_up_factor", first_step_give_up_factor, 0.0,
                      100.0),
       }) {
    if (!s.ok()) return s;
  }
  // Below 1 it would end readings the limits themselves accept.
  if (first_step_give_up_factor > 0.0 && first_step_give_up_factor < 1.0) {
    return absl::InvalidArgumentError(
        absl::StrCat("refinement.first_step_give_up_factor=", first_step_give_up_factor,
                     " is in (0, 1): 0 turns it off, else >= 1"));
  }
  return absl::OkStatus();
}

namespace {

// One refinement step: the face's plane from its interior points, each
// side measured (free, seam, continuing, occluded), and the pose moved onto
// the plane and the measured sides. False when the face has too few points.
bool RefineStep(const DepthImage& depth, const BoxDims& dims, BoxFace grasp_face,
                const RefinementOptions& options, Eigen::Isometry3d& pose,
                RefinementResult& result) {
  FaceFrame f = MakeFaceFrame(pose, dims, grasp_face);
  thread_local FacePoints face;  // reused: its vectors keep their capacity
  CollectFacePoints(depth, f, options.side_band_m, options.plane_tolerance_m, &face);
  const double pixel_m = f.c.z() / depth.camera.fx;  // point spacing on the face
  // Plane through the interior points: their scatter about the mean is
  // sum(q q^T) - n mean mean^T (face coordinates are centimetres to a
  // metre, so the difference loses nothing that matters in doubles).
  const int n = face.interior;
  if (n < 30) return false;
  const Eigen::Vector3d mean = face.sum / n;
  const Eigen::Matrix3d cov = face.sum_outer - n * mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal_local = eig.eigenvectors().col(0);
  if (normal_local.z() < 0.0) normal_local = -normal_local;
  result.plane_rms_m = std::sqrt(std::max(0.0, eig.eigenvalues()(0)) / n);
  result.face_points = n;
  face.seam_depth_m =
      std::max(options.min_seam_depth_m, options.seam_depth_per_rms * result.plane_rms_m);

  // Sides: +a, -a, +b, -b.
  SideMeasure pa = MeasureSide(face, true, 1.0, f.half_a, f.half_b, pixel_m, options);
  SideMeasure ma = MeasureSide(face, true, -1.0, f.half_a, f.half_b, pixel_m, options);
  SideMeasure pb = MeasureSide(face, false, 1.0, f.half_b, f.half_a, pixel_m, options);
  SideMeasure mb = MeasureSide(face, false, -1.0, f.half_b, f.half_a, pixel_m, options);
  // Where the depth shows the face running on with no seam, a straight
  // line in the colour image along the whole side is one.
  if (depth.has_grey()) {
    // Only a face with a depth seam is asked about (most have none).
    const bool depth_seam = pa.kind == SideKind::kSeam || ma.kind == SideKind::kSeam ||
                            pb.kind == SideKind::kSeam || mb.kind == SideKind::kSeam;
    if (depth_seam && options.colour_confirms_seam > 0.0 &&
        ColourVariesAroundFace(depth, f, options)) {
      ConfirmSeamInColour(depth, f, true, 1.0, options, &pa);
      ConfirmSeamInColour(depth, f, true, -1.0, options, &ma);
      ConfirmSeamInColour(depth, f, false, 1.0, options, &pb);
      ConfirmSeamInColour(depth, f, false, -1.0, options, &mb);
    }
    ColourSeamSide(depth, f, true, 1.0, options, &pa);
    ColourSeamSide(depth, f, true, -1.0, options, &ma);
    ColourSeamSide(depth, f, false, 1.0, options, &pb);
    ColourSeamSide(depth, f, false, -1.0, options, &mb);
  }
  const std::array<SideMeasure*, 4> sides = {&pa, &ma, &pb, &mb};
  OutwardSeamsNeedEverySide(sides);
  if (options.rim_ends_side) {
    RimAsFree(sides, f.half_a, f.half_b, options, [&](int i) {
      return FurtherShare(depth, f, i, sides[i]->inner, options.side_band_m,
                          options.plane_tolerance_m);
    });
  }
  PartlyEndedNeedsTwoMore(sides);
  result.sides = {pa.kind, ma.kind, pb.kind, mb.kind};
  result.seen_through = {pa.seen_through, ma.seen_through, pb.seen_through, mb.seen_through};
  result.free_sides = 0;
  for (SideKind k : result.sides) result.free_sides += k == SideKind::kFree;
  auto offset = [](const SideMeasure& plus, const SideMeasure& minus, double half) {
    if (plus.measured() && minus.measured()) return 0.5 * (plus.position - minus.position);
    if (plus.measured()) return plus.position - half;
    if (minus.measured()) return half - minus.position;
    return 0.0;
  };
  const double da = offset(pa, ma, f.half_a);
  const double db = offset(pb, mb, f.half_b);
  result.extent_a_m = pa.measured() && ma.measured() ? pa.position + ma.position : 0.0;
  result.extent_b_m = pb.measured() && mb.measured() ? pb.position + mb.position : 0.0;
  // Turn about the normal: a side along b (the +-a sides) turning by
  // slope s means the a axis turns by -s toward b... the median of every
  // side's: a free side's, and a seam's where it has one
  // (RefinementOptions::seam_turn_min_length_m).
  std::vector<double> turns;
  for (const auto& [m, s] :
       {std::pair{&pa, -1.0}, std::pair{&ma, 1.0}, std::pair{&pb, 1.0}, std::pair{&mb, -1.0}}) {
    if (m->kind == SideKind::kFree) turns.push_back(s * m->slope);
    if (m->kind == SideKind::kSeam && m->seam_slope) turns.push_back(s * *m->seam_slope);
  }
  double turn = 0.0;
  if (!turns.empty()) turn = std::atan(Median(turns));

  // New face frame.
  const Eigen::Vector3d n_cam =
      (normal_local.x() * f.a + normal_local.y() * f.b + normal_local.z() * f.n).normalized();
  Eigen::Vector3d a_cam = (std::cos(turn) * f.a + std::sin(turn) * f.b);
  a_cam = (a_cam - a_cam.dot(n_cam) * n_cam).normalized();
  const Eigen::Vector3d b_cam = f.sign_n * n_cam.cross(a_cam);  // keeps R right-handed
  const Eigen::Vector3d mean_cam = f.c + mean.x() * f.a + mean.y() * f.b + mean.z() * f.n;
  Eigen::Vector3d centre = f.c + da * f.a + db * f.b;
  centre += (mean_cam - centre).dot(n_cam) * n_cam;  // onto the fitted plane

  Eigen::Matrix3d R;
  R.col(f.axis_n) = f.sign_n * n_cam;
  R.col(f.axis_a) = a_cam;
  R.col(f.axis_b) = b_cam;
  pose.linear() = R;
  pose.translation() = centre - n_cam * dims[f.axis_n] / 2.0;
  return true;
}

// Free sides whose edge is the border of a shadow cast by something
// standing over the face are no edges of it: they become kOccluded.
void MarkShadowedSides(const DepthImage& depth, const BoxDims& dims, BoxFace grasp_face,
                       const RefinementOptions& options, const Eigen::Isometry3d& pose,
                       RefinementResult& result) {
  const FaceFrame f = MakeFaceFrame(pose, dims, grasp_face);
  const Eigen::Vector3d across[4] = {f.a, -f.a, f.b, -f.b};
  const Eigen::Vector3d along[4] = {f.b, f.b, f.a, f.a};
  const double half_across[4] = {f.half_a, f.half_a, f.half_b, f.half_b};
  const double half_along[4] = {f.half_b, f.half_b, f.half_a, f.half_a};
  for (int i = 0; i < 4; ++i) {
    if (result.sides[i] == SideKind::kFree &&
        ShadowedByOccluder(depth, f.c + half_across[i] * across[i], across[i], along[i],
                           half_along[i], options, f.n)) {
      result.sides[i] = SideKind::kOccluded;
      --result.free_sides;
    }
  }
}

// RefinementResult::past_gap: where the face's plane goes on past a gap
// beyond each free side (PlaneGoesOnPastGap), on faces with two opposite
// free sides.
void MarkGapsPastFreeSides(const DepthImage& depth, const BoxDims& dims, BoxFace grasp_face,
                           const RefinementOptions& options, const Eigen::Isometry3d& pose,
                           RefinementResult& result) {
  if (options.slat_gap_max_m <= 0.0) return;
  const FaceFrame f = MakeFaceFrame(pose, dims, grasp_face);
  const Eigen::Vector3d across[4] = {f.a, -f.a, f.b, -f.b};
  const Eigen::Vector3d along[4] = {f.b, f.b, f.a, f.a};
  const double half_across[4] = {f.half_a, f.half_a, f.half_b, f.half_b};
  const double half_along[4] = {f.half_b, f.half_b, f.half_a, f.half_a};
  for (int pair = 0; pair < 4; pair += 2) {
    if (result.sides[pair] != SideKind::kFree || result.sides[pair + 1] != SideKind::kFree)
      continue;
    for (int i = pair; i < pair + 2; ++i) {
      result.past_gap[i] = PlaneGoesOnPastGap(depth, f.c + half_across[i] * across[i], across[i],
                                              along[i], half_along[i], options, f.n);
    }
  }
}

// Continuing sides become kTiled where the layer they run on tiles with
// whole boxes, and with fewer than any other reading of the face (see
// the comment inside).
void TileContinuingSides(const DepthImage& depth, const BoxDims& dims, BoxFace grasp_face,
                         const RefinementOptions& options, const Eigen::Isometry3d& pose,
                         RefinementResult& result) {
  // Sides where the face runs on without a visible seam (pallet layers with
  // fine gaps): the face may be one tile of a layer of touching boxes, or a
  // part of a bigger face. The coplanar run through the box is measured to
  // the layer's ends along both of the face's axes; the hypothesis must
  // tile it with whole boxes, and with fewer boxes (fewer unseen seams) than
  // any other pair of the box's sides does. A top face twice a side's width
  // is then one face, not two; a pallet layer of 4 x 4 cartons is not read
  // as 8 x 4 cartons on their sides. Its continuing sides count as kTiled.
  const bool runs_on = std::any_of(result.sides.begin(), result.sides.end(),
                                   [](SideKind k) { return k == SideKind::kContinues; });
  // Only on a face that shows a seam (depth or colour) on another side: a
  // plane known to be made of boxes. A flat plane with no seam anywhere (a
  // laptop lid, a table top, a wall) is not tiled into boxes.
  const bool seamed = std::any_of(result.sides.begin(), result.sides.end(),
                                  [](SideKind k) { return k == SideKind::kSeam; });
  if (runs_on && (seamed || options.tile_uncued_sides) && options.max_tile_march_m > 0.0) {
    const FaceFrame f = MakeFaceFrame(pose, dims, grasp_face);
    const Eigen::Vector3d axis_dir[2] = {f.a, f.b};
    const double size[2] = {2 * f.half_a, 2 * f.half_b};
    // Per axis, the run of the plane through the box along three lines:
    // past a continuing side, and past a seam too (the layer goes on beyond
    // a touching box; a false seam in the middle of a face must not make a
    // box-wide strip of it).
    std::array<std::array<double, 3>, 2> extent = {
        {{size[0], size[0], size[0]}, {size[1], size[1], size[1]}}};
    bool measured = true;
    // Past each continuing side the layer must run on for a whole number
    // of tiles too (none: it ends within tile_tolerance_m): the extent
    // alone does not change as a box slides along a row between two
    // continuing sides, so it does not place the box.
    bool on_tile_bounds = true;
    for (int ax = 0; ax < 2 && measured; ++ax) {
      for (int sgn = 0; sgn < 2 && measured; ++sgn) {
        const SideKind kind = result.sides[2 * ax + sgn];
        if (kind != SideKind::kContinues && kind != SideKind::kSeam) continue;
        const Eigen::Vector3d across = sgn == 0 ? axis_dir[ax] : -axis_dir[ax];
        const auto runs = LayerRunsBeyond(depth, f.c + 0.5 * size[ax] * across, across,
                                          axis_dir[1 - ax], 0.5 * size[1 - ax], f.n, options);
        if (!runs) {
          // Past a seam the layer may leave the image: it then says nothing.
          if (kind == SideKind::kSeam) continue;
          measured = false;
          break;
        }
        for (int l = 0; l < 3; ++l) {
          extent[ax][l] += (*runs)[l] + options.tile_gap_m;
          if (kind == SideKind::kContinues && (*runs)[l] > options.tile_tolerance_m &&
              TileCount((*runs)[l], size[ax], options.tile_tolerance_m, options) == 0) {
            on_tile_bounds = false;
          }
        }
      }
    }
    // Tiles of (tile_a, tile_b) covering the longest runs, or 0 when some
    // run is not a whole number of them.
    // The hypothesis must tile within tile_tolerance_m; another reading of
    // the face counts as possible within twice that (precision first).
    auto tiling = [&](double tile_a, double tile_b, double tolerance) {
      int count[2] = {0, 0};
      const double tile[2] = {tile_a, tile_b};
      for (int ax = 0; ax < 2; ++ax) {
        for (double e : extent[ax]) {
          const int n = TileCount(e, tile[ax], tolerance, options);
          if (n == 0) return 0;
          count[ax] = std::max(count[ax], n);
        }
      }
      return count[0] * count[1];
    };
    const int tiles =
        measured && on_tile_bounds ? tiling(size[0], size[1], options.tile_tolerance_m) : 0;
    bool fewest = tiles > 0;
    for (int i = 0; i < 3 && fewest; ++i) {
      for (int j = 0; j < 3 && fewest; ++j) {
        if (i == j || (std::abs(dims[i] - size[0]) < 1e-6 && std::abs(dims[j] - size[1]) < 1e-6)) {
          continue;
        }
        const int other = tiling(dims[i], dims[j], 2.0 * options.tile_tolerance_m);
        if (other > 0 && other <= tiles) fewest = false;
      }
    }
    if (fewest) {
      for (SideKind& k : result.sides) {
        if (k == SideKind::kContinues) k = SideKind::kTiled;
      }
    }
  }
}

// After the first step: a side runs on flat, no side shows a seam (so no
// tiling can make it a tile: TileContinuingSides), and the step moved the
// pose less than end_on_flat_shift_m, so the second step reads the same
// bands and the hypothesis is declined for the side on flat (two thirds of
// all refined hypotheses are). One the step moved further may read its
// sides differently from where it lands.
// Whether `pose` moved from `initial` by more than `factor` times the
// largest correction a refinement accepts (max_shift_m, max_turn_deg).
bool MovedFurtherThan(const RefinementOptions& options, double factor,
                      const Eigen::Isometry3d& pose, const Eigen::Isometry3d& initial) {
  const double turn_deg = Eigen::AngleAxisd(initial.linear().transpose() * pose.linear()).angle() *
                          180.0 / std::numbers::pi;
  return (pose.translation() - initial.translation()).norm() > factor * options.max_shift_m ||
         turn_deg > factor * options.max_turn_deg;
}

bool EndsOnFlat(const RefinementResult& result, const RefinementOptions& options,
                const Eigen::Isometry3d& pose, const Eigen::Isometry3d& initial) {
  if (options.end_on_flat_shift_m <= 0.0 || options.tile_uncued_sides) return false;
  bool continues = false;
  for (SideKind k : result.sides) {
    if (k == SideKind::kSeam) return false;
    continues |= k == SideKind::kContinues;
  }
  return continues &&
         (pose.translation() - initial.translation()).norm() < options.end_on_flat_shift_m;
}

}  // namespace

RefinementResult RefineOnGraspFace(const DepthImage& depth, const BoxDims& dims, BoxFace grasp_face,
                                   const RefinementOptions& options,
                                   Eigen::Isometry3d* camera_T_box) {
  RefinementResult result;
  const Eigen::Isometry3d initial = *camera_T_box;
  Eigen::Isometry3d pose = initial;
  // Still turning after the last planned iteration: one more
  // (RefinementOptions::extra_step_corner_move_m), by how far the turn moved
  // the face's corners (its half diagonal times the turn).
  const FaceFrame face = MakeFaceFrame(initial, dims, grasp_face);
  const double half_diagonal = std::hypot(face.half_a, face.half_b);
  int iterations = std::max(1, options.iterations);
  for (int it = 0; it < iterations; ++it) {
    const Eigen::Matrix3d before = pose.linear();
    if (!RefineStep(depth, dims, grasp_face, options, pose, result)) return result;
    ++result.steps;
    if (it == options.iterations - 1 && it > 0 && options.extra_step_corner_move_m > 0.0 &&
        half_diagonal * Eigen::AngleAxisd(before.transpose() * pose.linear()).angle() >
            options.extra_step_corner_move_m) {
      ++iterations;
    }
    // RefinementOptions::first_step_give_up_factor: the steps after it
    // would not bring it back.
    if (it == 0 && options.iterations > 1 && options.first_step_give_up_factor > 0.0 &&
        MovedFurtherThan(options, options.first_step_give_up_factor, pose, initial)) {
      return result;  // not ok: moved too far
    }
    if (it == 0 && options.iterations > 1 && EndsOnFlat(result, options, pose, initial)) {
      *camera_T_box = pose;
      result.ok = true;  // read, and declined for the side on flat
      return result;
    }
  }
  // A reading that moved too far is not this box: its sides are not worth
  // the shadow and tiling checks (a third of all refinements end here).
  if (MovedFurtherThan(options, 1.0, pose, initial)) return result;
  MarkShadowedSides(depth, dims, grasp_face, options, pose, result);
  TileContinuingSides(depth, dims, grasp_face, options, pose, result);
  MarkGapsPastFreeSides(depth, dims, grasp_face, options, pose, result);
  *camera_T_box = pose;
  result.ok = true;
  return result;
}

}  // namespace cornerpose
