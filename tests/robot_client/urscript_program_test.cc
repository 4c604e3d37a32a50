// RenderPickProgram: the exact text for a fixed plan, the structure of every
// rendered program, pose literals that parse back to the planned rotations
// (including rotations near 180 degrees), and bad names refused.
#include "robot_client/planning/urscript_program.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "robot_client/ur/pose.h"
#include "tests/robot_client/test_poses.h"

namespace cornerpose::robot_client {
namespace {

using testing::ToolDownAt;

using ::testing::HasSubstr;

PickPlan FixedPlan() {
  PickPlan plan;
  plan.grasp = ToolDownAt(0.1, -0.5, 0.15);
  plan.approach = ToolDownAt(0.1, -0.5, 0.25);
  plan.retrieve = ToolDownAt(0.1, -0.5, 0.4);
  plan.place = ToolDownAt(-0.32, 0.4, 0.15);
  plan.place_above = ToolDownAt(-0.32, 0.4, 0.25);
  // The free moves' targets: the planner's IK solutions for M and place_above.
  plan.approach_joints = {-1.2, -1.6, 1.5, -1.5, -1.5708, 0.3};
  plan.place_above_joints = {1.9, -1.4, 1.2, -1.4, -1.5708, 0.25};
  return plan;
}

GripperOptions Gripper() {
  GripperOptions gripper;
  gripper.flange_T_tcp.translation() = Eigen::Vector3d(0, 0, 0.1);
  return gripper;
}

const ur::Joints kClear = {-1.9615, -1.8673, 1.3887, -1.0921, -1.5708, -0.3907};

TEST(UrscriptProgramTest, FixedPlanRendersExactly) {
  absl::StatusOr<std::string> text =
      RenderPickProgram("pick_0001", FixedPlan(), Gripper(), MotionOptions(), kClear);
  ASSERT_TRUE(text.ok()) << text.status();
  EXPECT_EQ(*text,
            R"(def pick_0001():
  set_tcp(p[0.000000, 0.000000, 0.100000, 0.000000, 0.000000, 0.000000])
  textmsg("pick_0001: start")
  movej([-1.200000, -1.600000, 1.500000, -1.500000, -1.570800, 0.300000], a=1.4, v=1.05)
  movel(p[0.100000, -0.500000, 0.150000, 3.141593, 0.000000, 0.000000], a=0.5, v=0.1)
  set_tool_digital_out(0, True)
  sleep(0.3)
  movel(p[0.100000, -0.500000, 0.400000, 3.141593, 0.000000, 0.000000], a=0.5, v=0.1)
  movej([1.900000, -1.400000, 1.200000, -1.400000, -1.570800, 0.250000], a=1.4, v=1.05)
  movel(p[-0.320000, 0.400000, 0.150000, 3.141593, 0.000000, 0.000000], a=0.5, v=0.1)
  set_tool_digital_out(0, False)
  sleep(0.3)
  movel(p[-0.320000, 0.400000, 0.250000, 3.141593, 0.000000, 0.000000], a=0.5, v=0.1)
  movej([-1.961500, -1.867300, 1.388700, -1.092100, -1.570800, -0.390700], a=1.4, v=1.05)
  textmsg("pick_0001: done")
end
)");
}

TEST(UrscriptProgramTest, StandardOutputSpeedsAndWaitsComeFromTheOptions) {
  GripperOptions gripper = Gripper();
  gripper.suction_output = SuctionOutputKind::kStandard;
  gripper.suction_output_index = 3;
  gripper.grasp_settle_s = 0.55;
  gripper.release_s = 2.0;
  MotionOptions motion;
  motion.joint_speed_rad_s = 0.5;
  motion.joint_acceleration_rad_s2 = 0.75;
  motion.linear_speed_m_s = 0.025;
  motion.linear_acceleration_m_s2 = 0.125;
  absl::StatusOr<std::string> text = RenderPickProgram("job", FixedPlan(), gripper, motion, kClear);
  ASSERT_TRUE(text.ok()) << text.status();
  EXPECT_THAT(*text, HasSubstr("  set_standard_digital_out(3, True)\n  sleep(0.55)\n"));
  EXPECT_THAT(*text, HasSubstr("  set_standard_digital_out(3, False)\n  sleep(2.0)\n"));
  EXPECT_THAT(*text, HasSubstr(", a=0.75, v=0.5)\n"));
  EXPECT_THAT(*text, HasSubstr(", a=0.125, v=0.025)\n"));
  EXPECT_EQ(text->find("set_tool_digital_out"), std::string::npos);
  EXPECT_EQ(text->find("${"), std::string::npos);
}

TEST(UrscriptProgramTest, BadNamesAreRefused) {
  for (const std::string& name :
       {std::string(""), std::string("1pick"), std::string("pick-1"), std::string("pick 1"),
        std::string("pick()"), std::string(32, 'a'),
        std::string("p\xc3\xaf"
                    "ck")}) {
    SCOPED_TRACE(name);
    absl::StatusOr<std::string> text =
        RenderPickProgram(name, FixedPlan(), Gripper(), MotionOptions(), kClear);
    EXPECT_EQ(text.status().code(), absl::StatusCode::kInvalidArgument) << text.status();
  }
  for (const std::string& name : {std::string("_x"), std::string("Pick7"), std::string(31, 'a')}) {
    EXPECT_TRUE(ValidateProgramName(name).ok()) << name;
  }
  EXPECT_EQ(PickProgramName(7), "pick_0007");
  EXPECT_TRUE(ValidateProgramName(PickProgramName(123456)).ok());
}

TEST(UrscriptProgramTest, NonFinitePoseIsRefused) {
  PickPlan plan = FixedPlan();
  plan.place.translation().x() = std::nan("");
  EXPECT_EQ(RenderPickProgram("p", plan, Gripper(), MotionOptions(), kClear).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// The six numbers of every pose literal in `text`, in order.
std::vector<ur::UrPose> PoseLiterals(const std::string& text) {
  std::vector<ur::UrPose> out;
  const std::regex literal(R"(p\[([^\]]*)\])");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), literal);
       it != std::sregex_iterator(); ++it) {
    const std::vector<std::string> parts = absl::StrSplit((*it)[1].str(), ", ");
    EXPECT_EQ(parts.size(), 6u);
    double v[6] = {};
    for (size_t i = 0; i < 6 && i < parts.size(); ++i) {
      EXPECT_TRUE(absl::SimpleAtod(parts[i], &v[i])) << parts[i];
    }
    out.push_back({Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5])});
  }
  return out;
}

TEST(UrscriptProgramTest, StructureAndPoseLiteralsParseBack) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Matrix3d> rotations;
  // Tool-down grasps (180 degrees about a horizontal axis) at many yaws, and
  // rotations just short of and at 180 degrees about random axes.
  for (double yaw = -M_PI; yaw <= M_PI; yaw += M_PI / 8) {
    rotations.push_back(ToolDownAt(0, 0, 0, yaw).linear());
  }
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d axis = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const double angle = i % 2 == 0 ? M_PI : M_PI - 1e-7 * (i + 1);
    rotations.push_back(Eigen::AngleAxisd(angle, axis).toRotationMatrix());
  }
  for (size_t i = 0; i < rotations.size(); ++i) {
    SCOPED_TRACE(i);
    PickPlan plan = FixedPlan();
    plan.grasp.linear() = rotations[i];
    plan.place.linear() = rotations[(i + 3) % rotations.size()];
    absl::StatusOr<std::string> text =
        RenderPickProgram("pick_0002", plan, Gripper(), MotionOptions(), kClear);
    ASSERT_TRUE(text.ok()) << text.status();

    // ASCII, "def"/"end" in column 1, body indented by two, final newline.
    for (char c : *text) ASSERT_TRUE(static_cast<unsigned char>(c) < 0x80 && c != '\t');
    ASSERT_EQ(text->back(), '\n');
    const std::vector<std::string> lines = absl::StrSplit(text->substr(0, text->size() - 1), '\n');
    ASSERT_EQ(lines.size(), 16u);
    EXPECT_EQ(lines.front(), "def pick_0002():");
    EXPECT_EQ(lines.back(), "end");
    for (size_t k = 1; k + 1 < lines.size(); ++k) {
      EXPECT_EQ(lines[k].substr(0, 2), "  ");
      EXPECT_NE(lines[k][2], ' ');
    }

    // tcp_offset, G, R, F, place_above: in program order (M and the first
    // place_above are joint vectors).
    const std::vector<ur::UrPose> literals = PoseLiterals(*text);
    ASSERT_EQ(literals.size(), 5u);
    const Eigen::Isometry3d expected[] = {Gripper().flange_T_tcp, plan.grasp, plan.retrieve,
                                          plan.place, plan.place_above};
    for (size_t k = 0; k < 5; ++k) {
      const Eigen::Isometry3d back = ur::FromUrPose(literals[k]);
      EXPECT_LE(literals[k].rotation.norm(), M_PI + 1e-6);
      EXPECT_LT(ur::RotationAngleBetween(Eigen::Quaterniond(back.linear()),
                                         Eigen::Quaterniond(expected[k].linear())),
                1e-5)
          << k;
      EXPECT_LT((back.translation() - expected[k].translation()).norm(), 1e-6) << k;
    }
  }
}

}  // namespace
}  // namespace cornerpose::robot_client
