#include "robot_client/ur/kinematics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace cornerpose::ur {
namespace {

constexpr double kPi = std::numbers::pi;

double RotationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return RotationAngleBetween(Eigen::Quaterniond(a.linear()), Eigen::Quaterniond(b.linear()));
}

double PoseDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm() + RotationError(a, b);
}

TEST(ArmModel, ParseAndName) {
  EXPECT_EQ(*ParseArmModel("ur5"), ArmModel::kUr5);
  EXPECT_EQ(*ParseArmModel("UR5e"), ArmModel::kUr5e);
  EXPECT_EQ(ParseArmModel("ur10").status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ParseArmModel("").status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_STREQ(ArmModelName(ArmModel::kUr5), "ur5");
  EXPECT_STREQ(ArmModelName(ArmModel::kUr5e), "ur5e");
  EXPECT_EQ(NominalDh(ArmModel::kUr5e).d[0], 0.1625);
  EXPECT_EQ(NominalDh(ArmModel::kUr5).a[2], -0.39225);
}

// ur-interface.md section 4, check 1: URSim 5.8 UR5e, recorded packet.
TEST(ForwardKinematics, Ur5eUrsimPacketExact) {
  const Joints q = {-1.6006999999999998, -1.7271, -2.2029999999999994,
                    -0.8079999999999998, 1.5951,  -0.030999999999999694};
  UrPose reported;
  reported.position << -0.14396865671352163, -0.43562006080319216, 0.2020300254283846;
  reported.rotation << -0.0012213596815925638, 3.1162765284819756, 0.038891915636886834;
  const Eigen::Isometry3d T = ForwardKinematics(ArmModel::kUr5e, q);
  EXPECT_LT((T.translation() - reported.position).norm(), 1e-9);
  EXPECT_LT(RotationError(T, FromUrPose(reported)), 1e-9);
}

// Check 2: UR5 CB2 controller packet from 2013 (per-robot calibration: mm).
TEST(ForwardKinematics, Ur5Cb2PacketWithinCalibration) {
  const Joints q = {-3.859885325398998,  -2.262535292828023, 2.391686075850997,
                    -1.9961094698395456, 2.8755209057205486, -2.082074328305076};
  UrPose reported;
  reported.position << 0.17079748121924124, -0.10959361590609135, 0.41373163491905257;
  reported.rotation << 1.3065256631795277, -0.3989354110254162, -0.84890166395034;
  const Eigen::Isometry3d T = ForwardKinematics(ArmModel::kUr5, q);
  EXPECT_LT((T.translation() - reported.position).norm(), 3e-3);
  EXPECT_LT(RotationError(T, FromUrPose(reported)), 1e-6);
  EXPECT_NEAR(T.translation().x(), 0.171742, 1e-6);
  EXPECT_NEAR(T.translation().y(), -0.110605, 1e-6);
  EXPECT_NEAR(T.translation().z(), 0.414271, 1e-6);
}

// Check 3: closed forms.
TEST(ForwardKinematics, ClosedForms) {
  for (ArmModel model : {ArmModel::kUr5, ArmModel::kUr5e}) {
    SCOPED_TRACE(ArmModelName(model));
    const DhParameters& dh = NominalDh(model);
    const double d1 = dh.d[0], a2 = dh.a[1], a3 = dh.a[2], d4 = dh.d[3], d5 = dh.d[4], d6 = dh.d[5];
    const Eigen::Isometry3d zero = ForwardKinematics(model, {0, 0, 0, 0, 0, 0});
    EXPECT_LT((zero.translation() - Eigen::Vector3d(a2 + a3, -(d4 + d6), d1 - d5)).norm(), 1e-12);
    EXPECT_LT((ToUrPose(zero).rotation - Eigen::Vector3d(kPi / 2, 0, 0)).norm(), 1e-12);
    const Eigen::Isometry3d bent =
        ForwardKinematics(model, {kPi / 2, -kPi / 4, kPi / 2, -kPi / 4, 0, 0});
    const Eigen::Vector3d expected(d4 + d6, (a2 + a3) / std::sqrt(2.0),
                                   d1 - a2 / std::sqrt(2.0) + a3 / std::sqrt(2.0) - d5);
    EXPECT_LT((bent.translation() - expected).norm(), 1e-12);
  }
  // The document's numbers.
  EXPECT_LT((ForwardKinematics(ArmModel::kUr5, {0, 0, 0, 0, 0, 0}).translation() -
             Eigen::Vector3d(-0.81725, -0.19145, -0.005491))
                .norm(),
            1e-9);
  EXPECT_LT((ForwardKinematics(ArmModel::kUr5e, {kPi / 2, -kPi / 4, kPi / 2, -kPi / 4, 0, 0})
                 .translation() -
             Eigen::Vector3d(0.2329, -0.577848, 0.085993))
                .norm(),
            1e-6);
}

Joints RandomJoints(std::mt19937& rng, double range) {
  std::uniform_real_distribution<double> u(-range, range);
  return {u(rng), u(rng), u(rng), u(rng), u(rng), u(rng)};
}

TEST(InverseKinematics, RandomRoundTrips) {
  std::mt19937 rng(42);
  for (ArmModel model : {ArmModel::kUr5, ArmModel::kUr5e}) {
    int checked = 0;
    for (int i = 0; i < 1000; ++i) {
      const Joints q = RandomJoints(rng, i % 2 == 0 ? kPi : 2.0 * kPi);
      // Stay away from the wrist (sin q5 = 0), shoulder and elbow
      // singularities, where solutions merge and q is not recoverable.
      if (std::abs(std::sin(q[4])) < 0.05 || std::abs(std::sin(q[2])) < 0.05) continue;
      SCOPED_TRACE(::testing::Message()
                   << ArmModelName(model) << " q = " << FormatJointsLiteral(q));
      const Eigen::Isometry3d T = ForwardKinematics(model, q);
      const std::vector<Joints> all = InverseKinematicsAll(model, T);
      ASSERT_FALSE(all.empty());
      EXPECT_LE(all.size(), 8u);
      for (const Joints& s : all) EXPECT_LT(PoseDistance(ForwardKinematics(model, s), T), 1e-6);
      const absl::StatusOr<Joints> nearest = InverseKinematics(model, T, q);
      ASSERT_TRUE(nearest.ok()) << nearest.status();
      for (int j = 0; j < 6; ++j) EXPECT_NEAR((*nearest)[j], q[j], 1e-6) << "joint " << j;
      ++checked;
    }
    EXPECT_GT(checked, 500);
  }
}

TEST(InverseKinematics, GenericPoseHasEightSolutions) {
  const Joints q = {0.3, -1.2, 1.4, -1.7, 1.2, 0.4};
  const std::vector<Joints> all =
      InverseKinematicsAll(ArmModel::kUr5e, ForwardKinematics(ArmModel::kUr5e, q));
  EXPECT_EQ(all.size(), 8u);
  for (const Joints& s : all) {
    for (double v : s) {
      EXPECT_GT(v, -kPi - 1e-12);
      EXPECT_LE(v, kPi + 1e-12);
    }
  }
}

TEST(InverseKinematics, SeedPicksNearestWrappedBranch) {
  const Joints q = {0.3, -1.2, 1.4, -1.7, 1.2, 0.4};
  const Eigen::Isometry3d T = ForwardKinematics(ArmModel::kUr5, q);
  // Seed one turn back on joints 1 and 6: the answer follows the seed.
  Joints seed = q;
  seed[0] -= 2 * kPi;
  seed[5] -= 2 * kPi;
  const absl::StatusOr<Joints> s = InverseKinematics(ArmModel::kUr5, T, seed);
  ASSERT_TRUE(s.ok()) << s.status();
  for (int j = 0; j < 6; ++j) EXPECT_NEAR((*s)[j], seed[j], 1e-9);
  // A tighter joint range keeps every angle inside it.
  IkOptions tight;
  tight.joint_limit_rad = kPi;
  const absl::StatusOr<Joints> t = InverseKinematics(ArmModel::kUr5, T, seed, tight);
  ASSERT_TRUE(t.ok()) << t.status();
  for (int j = 0; j < 6; ++j) {
    EXPECT_LE(std::abs((*t)[j]), kPi + 1e-12);
  }
  EXPECT_LT(PoseDistance(ForwardKinematics(ArmModel::kUr5, *t), T), 1e-6);
}

TEST(InverseKinematics, WristSingularityStillReachesThePose) {
  const Joints q = {0.5, -1.0, 1.0, -1.5, 0.0, 0.7};  // sin q5 = 0
  const Eigen::Isometry3d T = ForwardKinematics(ArmModel::kUr5e, q);
  const absl::StatusOr<Joints> s = InverseKinematics(ArmModel::kUr5e, T, q);
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_LT(PoseDistance(ForwardKinematics(ArmModel::kUr5e, *s), T), 1e-6);
}

TEST(InverseKinematics, UnreachableIsOutOfRange) {
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() << 2.0, 0.0, 0.3;
  EXPECT_TRUE(InverseKinematicsAll(ArmModel::kUr5e, far).empty());
  EXPECT_EQ(InverseKinematics(ArmModel::kUr5e, far, Joints{}).status().code(),
            absl::StatusCode::kOutOfRange);
  // Wrist centre on the base axis: inside the d4 cylinder.
  Eigen::Isometry3d inside = Eigen::Isometry3d::Identity();
  inside.translation() << 0.0, 0.0, 0.5 + NominalDh(ArmModel::kUr5).d[5];
  EXPECT_EQ(InverseKinematics(ArmModel::kUr5, inside, Joints{}).status().code(),
            absl::StatusCode::kOutOfRange);
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation() << std::nan(""), 0.0, 0.0;
  EXPECT_EQ(InverseKinematics(ArmModel::kUr5, nan, Joints{}).status().code(),
            absl::StatusCode::kOutOfRange);
}

}  // namespace
}  // namespace cornerpose::ur
