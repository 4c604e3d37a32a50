#include "common/perception/layer_plane.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "common/perception/internal/grasp_face.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

using Face = internal::GraspFace;

// The variance of the points (count, sums, sums of products) about their
// best plane, and that plane's normal.
double SmallestVariance(double count, const Eigen::Vector3d& sum, const Eigen::Matrix3d& sum_outer,
                        Eigen::Vector3d* normal) {
  const Eigen::Vector3d mean = sum / count;
  const Eigen::Matrix3d cov = sum_outer / count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (normal != nullptr) *normal = eig.eigenvectors().col(0);
  return std::max(0.0, eig.eigenvalues()(0));
}

int Root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Adds the face's measured points that lie on its plane, more than
// side_margin inside its sides, to the sums.
void AddFacePixels(const DepthImage& depth, const Face& f, const LayerPlaneOptions& o, double* n,
                   Eigen::Vector3d* sum, Eigen::Matrix3d* sum_outer) {
  const double in_a = f.half_a - o.side_margin_m, in_b = f.half_b - o.side_margin_m;
  if (in_a <= 0.0 || in_b <= 0.0) return;
  std::vector<Eigen::Vector3d> outline;
  for (double sa : {-1.0, 1.0}) {
    for (double sb : {-1.0, 1.0}) outline.push_back(f.c + sa * in_a * f.a + sb * in_b * f.b);
  }
  const std::optional<PixelRect> rect = ProjectedRect(depth.camera, outline);
  if (!rect) return;
  for (int v = rect->v0; v <= rect->v1; ++v) {
    for (int u = rect->u0; u <= rect->u1; ++u) {
      const float z = depth.at(u, v);
      if (std::isnan(z)) continue;
      const Eigen::Vector3d p = z * PixelRay(depth.camera, u, v);
      const Eigen::Vector3d d = p - f.c;
      if (std::abs(d.dot(f.a)) > in_a || std::abs(d.dot(f.b)) > in_b ||
          std::abs(d.dot(f.n)) > o.plane_tolerance_m) {
        continue;
      }
      *n += 1.0;
      *sum += p;
      *sum_outer += p * p.transpose();
    }
  }
}

// Whether a face's pixels lie about a plane of normal `normal` (through
// their own centroid) within max_rms_ratio (plus 1 mm) of their rms about
// their own best plane: a tilt its noise allows. (`o` gives the pixels'
// side margin.)
bool FitsPlane(const DepthImage& depth, const Face& f, const Eigen::Vector3d& normal,
               const LayerPlaneOptions& o, double max_rms_ratio) {
  double c = 0.0;
  Eigen::Vector3d s1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();
  AddFacePixels(depth, f, o, &c, &s1, &s2);
  if (c < 30.0) return false;
  const double own_rms = std::sqrt(SmallestVariance(c, s1, s2, nullptr));
  const Eigen::Vector3d mean = s1 / c;
  const Eigen::Matrix3d cov = s2 / c - mean * mean.transpose();
  const double about_rms = std::sqrt(std::max(0.0, normal.dot(cov * normal)));
  return about_rms <= max_rms_ratio * own_rms + 0.001;
}

// Whether face f, tilted against the plane (normal, point), has its centre
// within `share` of the height its tilt lifts it to when it rests on the
// plane by its lowest edge (LayerPlaneOptions::rest_share).
bool InsidePlane(const Face& f, const Eigen::Vector3d& normal, const Eigen::Vector3d& point,
                 double share) {
  if (share <= 0.0) return false;
  const Eigen::Vector3d axis = f.n.cross(normal);  // the tilt's axis, |axis| = sin(tilt)
  const double sin_tilt = axis.norm();
  if (sin_tilt < 1e-6) return false;
  // The face's half extent across that axis, in its plane.
  const Eigen::Vector3d across = f.n.cross(axis / sin_tilt);
  const double half = f.half_a * std::abs(across.dot(f.a)) + f.half_b * std::abs(across.dot(f.b));
  return std::abs((f.c - point).dot(normal)) <= share * half * sin_tilt;
}

bool Touch(const Face& a, const Face& b, const LayerPlaneOptions& o) {
  return internal::FacesTouch(a, b, o.touch_factor);
}

}  // namespace

absl::Status LayerPlaneOptions::Validate() const {
  for (absl::Status s :
       {CheckRange("layer_plane.max_angle_deg", max_angle_deg, 0.0, 30.0),
        CheckPositive("layer_plane.plane_tolerance_m", plane_tolerance_m, 0.1),
        CheckPositive("layer_plane.touch_factor", touch_factor, 2.0),
        CheckRange("layer_plane.side_margin_m", side_margin_m, 0.0, 0.1),
        CheckRange("layer_plane.max_rms_ratio", max_rms_ratio, 1.0, 10.0),
        CheckRange("layer_plane.adopt_angle_deg", adopt_angle_deg, 0.0, 45.0),
        CheckRange("layer_plane.rest_share", rest_share, 0.0, 1.0),
        CheckRange("layer_plane.rest_max_rms_ratio", rest_max_rms_ratio, 1.0, 10.0)}) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

int AlignToLayerPlanes(const DepthImage& depth, const BoxDims& dims,
                       const LayerPlaneOptions& options, std::vector<DetectedBox>* boxes) {
  const int n = static_cast<int>(boxes->size());
  if (options.max_angle_deg <= 0.0 || n < 2) return 0;
  const double cos_max = std::cos(options.max_angle_deg * std::numbers::pi / 180.0);
  std::vector<Face> faces;
  faces.reserve(n);
  for (const DetectedBox& box : *boxes) faces.push_back(internal::GraspFaceOf(box, dims));
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const Face &fi = faces[i], &fj = faces[j];
      if (!internal::FacesOnOnePlane(fi, fj, cos_max, options.plane_tolerance_m) ||
          !Touch(fi, fj, options)) {
        continue;
      }
      parent[Root(parent, i)] = Root(parent, j);
    }
  }
  const double cos_adopt =
      std::cos(std::max(options.adopt_angle_deg, options.max_angle_deg) * std::numbers::pi / 180.0);
  // Turns box i onto the plane of `normal`, about its face centre, when
  // its face is within max_angle_deg of it, or within adopt_angle_deg and
  // its pixels fit the plane.
  // Each box's plane is chosen first and applied at the end: a small
  // group's plane may still give way to a bigger neighbour's.
  std::vector<char> taken(n, 0);
  std::vector<Eigen::Vector3d> chosen(n, Eigen::Vector3d::Zero());
  // A plane's normal, turned to face i's side.
  auto toward = [&](int i, const Eigen::Vector3d& normal) -> Eigen::Vector3d {
    return normal.dot(faces[i].n) < 0.0 ? -normal : normal;
  };
  auto take_plane = [&](int i, const Eigen::Vector3d& normal, bool rests_in_plane = false) {
    const Eigen::Vector3d to = toward(i, normal);
    const double cos_turn = to.dot(faces[i].n);
    if (cos_turn < cos_adopt ||
        (cos_turn < cos_max &&
         !FitsPlane(depth, faces[i], to, options,
                    rests_in_plane ? options.rest_max_rms_ratio : options.max_rms_ratio))) {
      return false;
    }
    chosen[i] = to;
    taken[i] = 1;
    return true;
  };
  struct Layer {
    Eigen::Vector3d normal, centroid;
    std::vector<int> members;
  };
  std::vector<Layer> layers;
  for (int root = 0; root < n; ++root) {
    if (Root(parent, root) != root) continue;
    std::vector<int> members;
    for (int i = 0; i < n; ++i) {
      if (Root(parent, i) == root) members.push_back(i);
    }
    if (members.size() < 2) continue;
    // Each face's pixels alone and all together: one plane must fit them
    // all about as well as each face's own (two faces tilted against each
    // other, a roof in a heap, do not share a plane).
    double count = 0.0, own_sq = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d sum_outer = Eigen::Matrix3d::Zero();
    for (int i : members) {
      double c = 0.0;
      Eigen::Vector3d s1 = Eigen::Vector3d::Zero();
      Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();
      AddFacePixels(depth, faces[i], options, &c, &s1, &s2);
      if (c < 30.0) continue;
      own_sq += c * SmallestVariance(c, s1, s2, nullptr);
      count += c;
      sum += s1;
      sum_outer += s2;
    }
    if (count < 60.0) continue;
    Eigen::Vector3d normal;
    const double joint_sq = SmallestVariance(count, sum, sum_outer, &normal);
    const double own_rms = std::sqrt(own_sq / count);
    if (std::sqrt(joint_sq) > options.max_rms_ratio * own_rms + 0.001) continue;
    for (int i : members) take_plane(i, normal);
    layers.push_back({normal, sum / count, std::move(members)});
  }
  // A group beside a bigger one takes its plane
  // (LayerPlaneOptions::merge_groups); the biggest first.
  std::sort(layers.begin(), layers.end(),
            [](const Layer& a, const Layer& b) { return a.members.size() > b.members.size(); });
  for (size_t small = 1; options.merge_groups && small < layers.size(); ++small) {
    Layer& s_layer = layers[small];
    for (size_t big = 0; big < small; ++big) {
      const Layer& b_layer = layers[big];
      if (b_layer.members.size() <= s_layer.members.size() ||
          std::abs(b_layer.normal.dot(s_layer.normal)) < cos_adopt ||
          std::abs((s_layer.centroid - b_layer.centroid).dot(b_layer.normal)) >
              options.plane_tolerance_m) {
        continue;
      }
      const bool touches = std::any_of(s_layer.members.begin(), s_layer.members.end(), [&](int j) {
        return std::any_of(b_layer.members.begin(), b_layer.members.end(),
                           [&](int i) { return Touch(faces[i], faces[j], options); });
      });
      const bool fits = std::all_of(s_layer.members.begin(), s_layer.members.end(), [&](int j) {
        const Eigen::Vector3d to = toward(j, b_layer.normal);
        return to.dot(faces[j].n) >= cos_adopt &&
               FitsPlane(depth, faces[j], to, options, options.max_rms_ratio);
      });
      if (!touches || !fits) continue;
      for (int j : s_layer.members) {
        chosen[j] = toward(j, b_layer.normal);
      }
      s_layer.normal = b_layer.normal;
      break;
    }
  }
  // Faces tilted past max_angle_deg that touch a layer's member with
  // their centre on its plane (they joined no group: their tilt is their
  // noise's) take it when their pixels fit it.
  if (cos_adopt < cos_max) {
    for (int j = 0; j < n; ++j) {
      if (taken[j]) continue;
      for (const Layer& layer : layers) {
        if (std::find(layer.members.begin(), layer.members.end(), j) != layer.members.end()) {
          continue;
        }
        const bool touches = std::any_of(layer.members.begin(), layer.members.end(),
                                         [&](int i) { return Touch(faces[i], faces[j], options); });
        if (!touches ||
            std::abs((faces[j].c - layer.centroid).dot(layer.normal)) > options.plane_tolerance_m) {
          continue;
        }
        if (take_plane(j, layer.normal,
                       InsidePlane(faces[j], layer.normal, layer.centroid, options.rest_share))) {
          break;
        }
      }
    }
  }
  // The smallest rotation taking each face's normal onto its plane's,
  // about the face centre.
  int turned = 0;
  for (int i = 0; i < n; ++i) {
    if (!taken[i]) continue;
    DetectedBox& box = (*boxes)[i];
    const Eigen::Matrix3d turn =
        Eigen::Quaterniond::FromTwoVectors(faces[i].n, chosen[i]).toRotationMatrix();
    const int axis = static_cast<int>(box.grasp_face) / 2;
    box.camera_T_box.linear() = turn * box.camera_T_box.linear();
    box.camera_T_box.translation() = box.grasp_centre_camera - chosen[i] * dims[axis] / 2.0;
    box.grasp_normal_camera = chosen[i];
    ++turned;
  }
  return turned;
}

}  // namespace cornerpose
