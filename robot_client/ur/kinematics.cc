#include "robot_client/ur/kinematics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"

namespace cornerpose::ur {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Isometry3d DhTransform(double a, double d, double alpha, double theta) {
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << ct, -st * ca, st * sa,  //
      st, ct * ca, -ct * sa,            //
      0.0, sa, ca;
  T.translation() << a * ct, a * st, d;
  return T;
}

// Into (-pi, pi].
double WrapPi(double angle) {
  double w = std::remainder(angle, 2.0 * kPi);
  if (w <= -kPi) w += 2.0 * kPi;
  return w;
}

bool Reproduces(const DhParameters& dh, const Joints& q, const Eigen::Isometry3d& target,
                const IkOptions& options) {
  const Eigen::Isometry3d T = ForwardKinematics(dh, q);
  if ((T.translation() - target.translation()).norm() > options.position_tolerance_m) return false;
  const double angle =
      RotationAngleBetween(Eigen::Quaterniond(T.linear()), Eigen::Quaterniond(target.linear()));
  return angle <= options.rotation_tolerance_rad;
}

// acos that accepts |x| slightly above 1 (rounding); nullopt-like NaN beyond.
double SafeAcos(double x, double slack) {
  if (x > 1.0 + slack || x < -1.0 - slack) return std::numeric_limits<double>::quiet_NaN();
  return std::acos(std::clamp(x, -1.0, 1.0));
}

}  // namespace

absl::StatusOr<ArmModel> ParseArmModel(absl::string_view name) {
  const std::string lower = absl::AsciiStrToLower(name);
  if (lower == "ur5") return ArmModel::kUr5;
  if (lower == "ur5e") return ArmModel::kUr5e;
  return absl::InvalidArgumentError(
      absl::StrCat("unknown arm model '", name, "' (expected ur5 or ur5e)"));
}

const char* ArmModelName(ArmModel model) {
  switch (model) {
    case ArmModel::kUr5:
      return "ur5";
    case ArmModel::kUr5e:
      return "ur5e";
  }
  return "unknown";
}

const DhParameters& NominalDh(ArmModel model) {
  // UR's published tables (CB3 manual appendix; universal-robots.com DH
  // article for the UR5e).
  static const DhParameters kUr5{
      .a = {0.0, -0.425, -0.39225, 0.0, 0.0, 0.0},
      .d = {0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823},
      .alpha = {kPi / 2, 0.0, 0.0, kPi / 2, -kPi / 2, 0.0},
  };
  static const DhParameters kUr5e{
      .a = {0.0, -0.425, -0.3922, 0.0, 0.0, 0.0},
      .d = {0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996},
      .alpha = {kPi / 2, 0.0, 0.0, kPi / 2, -kPi / 2, 0.0},
  };
  return model == ArmModel::kUr5 ? kUr5 : kUr5e;
}

Eigen::Isometry3d ForwardKinematics(const DhParameters& dh, const Joints& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) T = T * DhTransform(dh.a[i], dh.d[i], dh.alpha[i], q[i]);
  return T;
}

Eigen::Isometry3d ForwardKinematics(ArmModel model, const Joints& q) {
  return ForwardKinematics(NominalDh(model), q);
}

// Closed form for the UR geometry (a1 = a4 = a5 = a6 = 0, alpha = pi/2, 0,
// 0, pi/2, -pi/2, 0; Hawkins 2013). q1, q5, q6 come from the wrist-centre
// geometry; the remaining planar 3R problem (q2, q3, q4) is solved on
// T14 = T01^-1 T06 T56^-1 T45^-1 computed with the DH transforms themselves,
// so no sign is hand-derived there. Every candidate is checked with FK.
std::vector<Joints> InverseKinematicsAll(ArmModel model, const Eigen::Isometry3d& base_T_flange,
                                         const IkOptions& options) {
  const DhParameters& dh = NominalDh(model);
  const double d1 = dh.d[0], a2 = dh.a[1], a3 = dh.a[2], d4 = dh.d[3], d6 = dh.d[5];
  const Eigen::Matrix3d& R = base_T_flange.linear();
  const Eigen::Vector3d p06 = base_T_flange.translation();
  const Eigen::Vector3d p05 = p06 - d6 * R.col(2);
  std::vector<Joints> solutions;
  if (!p06.allFinite() || !R.allFinite()) return solutions;

  // q1: the wrist centre lies on the plane z1 . (p - o1) = d4, with
  // z1 = (sin q1, -cos q1, 0): r sin(q1 - psi) = d4.
  const double r = std::hypot(p05.x(), p05.y());
  if (r < std::abs(d4) || r < 1e-12) return solutions;
  const double psi = std::atan2(p05.y(), p05.x());
  const double beta = std::asin(d4 / r);
  const double q1_candidates[2] = {psi + beta, psi + kPi - beta};

  for (double q1 : q1_candidates) {
    const double s1 = std::sin(q1), c1 = std::cos(q1);
    // q5: cos q5 = z1 . z6, from the flange position's offset off that plane.
    const double c5 = (p06.x() * s1 - p06.y() * c1 - d4) / d6;
    const double q5_abs = SafeAcos(c5, 1e-9);
    if (std::isnan(q5_abs)) continue;
    for (double q5 : {q5_abs, -q5_abs}) {
      const double s5 = std::sin(q5);
      // q6: z1 seen from the flange is (s5 c6, -s5 s6, c5).
      double q6 = options.singular_q6;
      const Eigen::Vector3d w = R.transpose() * Eigen::Vector3d(s1, -c1, 0.0);
      if (std::abs(s5) > 1e-10) q6 = std::atan2(-w.y() / s5, w.x() / s5);

      const Eigen::Isometry3d T14 = DhTransform(dh.a[0], d1, dh.alpha[0], q1).inverse() *
                                    base_T_flange *
                                    DhTransform(dh.a[5], d6, dh.alpha[5], q6).inverse() *
                                    DhTransform(dh.a[4], dh.d[4], dh.alpha[4], q5).inverse();
      // Frame 3's origin: frame 4's minus d4 along the (common) z axis.
      const double x = T14.translation().x(), y = T14.translation().y();
      const double c3 = (x * x + y * y - a2 * a2 - a3 * a3) / (2.0 * a2 * a3);
      const double q3_abs = SafeAcos(c3, 1e-9);
      if (std::isnan(q3_abs)) continue;
      const double phi = std::atan2(T14.linear()(1, 0), T14.linear()(0, 0));
      for (double q3 : {q3_abs, -q3_abs}) {
        const double s3 = std::sin(q3);
        const double q2 = std::atan2(y, x) - std::atan2(a3 * s3, a2 + a3 * std::cos(q3));
        const double q4 = phi - q2 - q3;
        Joints q = {WrapPi(q1), WrapPi(q2), WrapPi(q3), WrapPi(q4), WrapPi(q5), WrapPi(q6)};
        if (Reproduces(dh, q, base_T_flange, options)) solutions.push_back(q);
      }
    }
  }
  return solutions;
}

absl::StatusOr<Joints> InverseKinematics(ArmModel model, const Eigen::Isometry3d& base_T_flange,
                                         const Joints& seed, const IkOptions& options) {
  const std::vector<Joints> solutions = InverseKinematicsAll(model, base_T_flange, options);
  if (solutions.empty()) {
    return absl::OutOfRangeError(absl::StrCat("pose ", FormatPoseLiteral(ToUrPose(base_T_flange)),
                                              " is not reachable by the ", ArmModelName(model),
                                              " flange"));
  }
  const double limit = options.joint_limit_rad;
  double best_distance = std::numeric_limits<double>::infinity();
  Joints best{};
  for (const Joints& solution : solutions) {
    Joints q{};
    double distance = 0.0;
    bool in_range = true;
    for (int i = 0; i < 6; ++i) {
      // The 2 pi shift of solution[i] nearest seed[i], then pulled inside
      // the joint range.
      double v = solution[i] + 2.0 * kPi * std::round((seed[i] - solution[i]) / (2.0 * kPi));
      while (v > limit + 1e-12) v -= 2.0 * kPi;
      while (v < -limit - 1e-12) v += 2.0 * kPi;
      if (v > limit + 1e-12) in_range = false;  // range narrower than 2 pi
      q[i] = v;
      distance += (v - seed[i]) * (v - seed[i]);
    }
    if (in_range && distance < best_distance) {
      best_distance = distance;
      best = q;
    }
  }
  if (!std::isfinite(best_distance)) {
    return absl::OutOfRangeError("no inverse kinematics solution within the joint limits");
  }
  return best;
}

}  // namespace cornerpose::ur
