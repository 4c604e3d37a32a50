#include "robot_client/ur/pose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace cornerpose::ur {
namespace {

constexpr double kPi = std::numbers::pi;

double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  // Independent of RotationAngleBetween: through the rotation matrices.
  const Eigen::Matrix3d d = a.toRotationMatrix().transpose() * b.toRotationMatrix();
  return std::acos(std::clamp((d.trace() - 1.0) / 2.0, -1.0, 1.0));
}

void ExpectRoundTrip(const Eigen::Quaterniond& q) {
  SCOPED_TRACE(::testing::Message() << "q = " << q.coeffs().transpose());
  const Eigen::Vector3d r = RotationVectorFromQuaternion(q);
  ASSERT_TRUE(r.allFinite());
  EXPECT_LE(r.norm(), kPi + 1e-15);
  const Eigen::Quaterniond back = QuaternionFromRotationVector(r);
  EXPECT_NEAR((q.normalized().toRotationMatrix() - back.toRotationMatrix()).norm(), 0.0, 1e-12);
  EXPECT_LE(AngleBetween(q.normalized(), back), 1e-7);  // acos resolution near 0
}

TEST(RotationVector, IdentityIsZero) {
  EXPECT_EQ(RotationVectorFromQuaternion(Eigen::Quaterniond::Identity()), Eigen::Vector3d::Zero());
  // -identity is the same rotation.
  EXPECT_EQ(RotationVectorFromQuaternion(Eigen::Quaterniond(-1, 0, 0, 0)), Eigen::Vector3d::Zero());
  EXPECT_TRUE(QuaternionFromRotationVector(Eigen::Vector3d::Zero())
                  .isApprox(Eigen::Quaterniond::Identity()));
}

TEST(RotationVector, KnownAngles) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -3).normalized();
  for (double angle : {1e-300, 1e-15, 1e-9, 1e-6, 0.3, 1.0, 2.5, kPi - 1e-6, kPi - 1e-9}) {
    SCOPED_TRACE(angle);
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, axis));
    const Eigen::Vector3d r = RotationVectorFromQuaternion(q);
    EXPECT_NEAR((r - angle * axis).norm(), 0.0, 1e-15 + 1e-14 * angle);
    ExpectRoundTrip(q);
  }
}

TEST(RotationVector, ExactlyPiIsFiniteAndLengthPi) {
  for (const Eigen::Vector3d& axis :
       std::vector<Eigen::Vector3d>{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                    Eigen::Vector3d(1, 1, 1).normalized()}) {
    const Eigen::Quaterniond q(0.0, axis.x(), axis.y(), axis.z());
    const Eigen::Vector3d r = RotationVectorFromQuaternion(q);
    ASSERT_TRUE(r.allFinite());
    EXPECT_NEAR(r.norm(), kPi, 1e-12);
    // r or -r: the same rotation.
    EXPECT_NEAR(std::abs(r.normalized().dot(axis)), 1.0, 1e-12);
    ExpectRoundTrip(q);
  }
}

TEST(RotationVector, NotNormalisedAndNegativeW) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  Eigen::Quaterniond scaled = q;
  scaled.coeffs() *= -3.0;
  const Eigen::Vector3d r = RotationVectorFromQuaternion(scaled);
  EXPECT_NEAR((r - Eigen::Vector3d(0, 0, 0.7)).norm(), 0.0, 1e-14);
  // Zero quaternion: no NaN.
  EXPECT_TRUE(RotationVectorFromQuaternion(Eigen::Quaterniond(0, 0, 0, 0)).allFinite());
}

TEST(RotationVector, RandomRoundTrips) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
    q.normalize();
    ExpectRoundTrip(q);
    // Rotation vectors with |r| < pi come back as themselves.
    const Eigen::Vector3d r = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() *
                              std::uniform_real_distribution<double>(0.0, kPi - 1e-3)(rng);
    EXPECT_NEAR((RotationVectorFromQuaternion(QuaternionFromRotationVector(r)) - r).norm(), 0.0,
                1e-12);
  }
}

TEST(RotationAngleBetween, MatchesMatrixAngle) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Quaterniond a = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    const Eigen::Quaterniond b = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    const double angle = RotationAngleBetween(a, b);
    EXPECT_GE(angle, 0.0);
    EXPECT_LE(angle, kPi);
    EXPECT_NEAR(angle, AngleBetween(a, b), 1e-6);
  }
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(RotationAngleBetween(a, Eigen::Quaterniond(-a.coeffs())), 0.0, 1e-15);
  EXPECT_NEAR(RotationAngleBetween(
                  a, a * Eigen::Quaterniond(Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitY()))),
              kPi, 1e-12);
}

TEST(UrPose, IsometryRoundTrip) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng));
    const Eigen::Isometry3d back = FromUrPose(ToUrPose(T));
    EXPECT_NEAR((back.matrix() - T.matrix()).norm(), 0.0, 1e-12);
  }
}

TEST(Literals, PoseAndJoints) {
  UrPose p;
  p.position = Eigen::Vector3d(0.1, -0.25, 1.0 / 3.0);
  p.rotation = Eigen::Vector3d(kPi, -1e-9, 0.0000016);
  EXPECT_EQ(FormatPoseLiteral(p), "p[0.100000, -0.250000, 0.333333, 3.141593, 0.000000, 0.000002]");
  EXPECT_EQ(FormatPoseLiteral(UrPose{}),
            "p[0.000000, 0.000000, 0.000000, 0.000000, 0.000000, 0.000000]");
  EXPECT_EQ(FormatJointsLiteral({-1.6007, -1.7271, -2.203, -0.808, 1.5951, -0.031}),
            "[-1.600700, -1.727100, -2.203000, -0.808000, 1.595100, -0.031000]");
}

}  // namespace
}  // namespace cornerpose::ur
