#include "robot_client/planning/urscript_program.h"

#include <cmath>
#include <utility>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_replace.h"

namespace cornerpose::robot_client {
namespace {

// The one template. Parameters (all substituted; units as in the header):
//   ${name}                program name, also in the start/done messages
//   ${tcp_offset}          flange -> TCP, pose literal (m, rad)
//   ${approach_joints}     M, joint vector literal (rad): the planned IK solution
//   ${approach}            M, pose literal, base frame (m, rad)
//   ${grasp}               G, pose literal
//   ${retrieve}            R, pose literal
//   ${transit_move}        "  movej(T's joints, ...)\n" when the plan has a
//                          transit waypoint T, else nothing
//   ${place_above_joints}  above F, joint vector literal (rad)
//   ${place_above}         above F, pose literal
//   ${place}               F, pose literal
//   ${clear_joints}        clear pose, joint vector literal (rad)
//   ${joint_speed}         movej v, rad/s
//   ${joint_acceleration}  movej a, rad/s^2
//   ${linear_speed}        movel v, m/s
//   ${linear_acceleration} movel a, m/s^2
//   ${suction_out}         set_tool_digital_out | set_standard_digital_out
//   ${suction_index}       that output's index
//   ${grasp_settle}        wait after vacuum on, s
//   ${release}             wait after vacuum off, s
constexpr absl::string_view kPickProgramTemplate = R"(def ${name}():
  set_tcp(${tcp_offset})
  textmsg("${name}: start")
  movej(${approach_joints}, a=${joint_acceleration}, v=${joint_speed})
  movel(${grasp}, a=${linear_acceleration}, v=${linear_speed})
  ${suction_out}(${suction_index}, True)
  sleep(${grasp_settle})
  movel(${retrieve}, a=${linear_acceleration}, v=${linear_speed})
${transit_move}  movej(${place_above_joints}, a=${joint_acceleration}, v=${joint_speed})
  movel(${place}, a=${linear_acceleration}, v=${linear_speed})
  ${suction_out}(${suction_index}, False)
  sleep(${release})
  movel(${place_above}, a=${linear_acceleration}, v=${linear_speed})
  movej(${clear_joints}, a=${joint_acceleration}, v=${joint_speed})
  textmsg("${name}: done")
end
)";

// A plain decimal with up to 6 places and no trailing zeros ("0.1", "1.05",
// "2.0"): URScript reads it, and the text stays short.
std::string FormatNumber(double v) {
  if (std::abs(v) < 5e-7) v = 0.0;
  std::string s = absl::StrFormat("%.6f", v);
  while (s.size() > 1 && s.back() == '0' && s[s.size() - 2] != '.') s.pop_back();
  return s;
}

}  // namespace

absl::Status ValidateProgramName(absl::string_view name) {
  if (name.empty()) return absl::InvalidArgumentError("program name is empty");
  if (name.size() > 31) {
    return absl::InvalidArgumentError(
        absl::StrCat("program name '", name, "' is longer than 31 characters"));
  }
  if (!(absl::ascii_isalpha(name[0]) || name[0] == '_')) {
    return absl::InvalidArgumentError(
        absl::StrCat("program name '", name, "' must start with a letter or an underscore"));
  }
  for (char c : name) {
    if (!(absl::ascii_isalnum(c) || c == '_')) {
      return absl::InvalidArgumentError(
          absl::StrCat("program name '", name, "' may hold only letters, digits and underscores"));
    }
  }
  return absl::OkStatus();
}

std::string PickProgramName(int pick_number) {
  return absl::StrFormat("pick_%04d", pick_number < 0 ? 0 : pick_number);
}

absl::StatusOr<std::string> RenderPickProgram(absl::string_view name, const PickPlan& plan,
                                              const GripperOptions& gripper,
                                              const MotionOptions& motion,
                                              const ur::Joints& clear_joints) {
  if (absl::Status s = ValidateProgramName(name); !s.ok()) return s;
  const std::vector<std::pair<const char*, const Eigen::Isometry3d*>> poses = {
      {"tcp_offset", &gripper.flange_T_tcp},
      {"approach", &plan.approach},
      {"grasp", &plan.grasp},
      {"retrieve", &plan.retrieve},
      {"place_above", &plan.place_above},
      {"place", &plan.place}};
  for (const auto& [what, pose] : poses) {
    if (!pose->matrix().allFinite()) {
      return absl::InvalidArgumentError(absl::StrCat("pose ", what, " is not finite"));
    }
  }
  for (const auto& [what, joints] :
       {std::pair<const char*, const ur::Joints*>{"clear joints", &clear_joints},
        {"approach joints", &plan.approach_joints},
        {"place_above joints", &plan.place_above_joints},
        {"transit joints", &plan.transit_joints}}) {
    for (double v : *joints) {
      if (!std::isfinite(v)) return absl::InvalidArgumentError(absl::StrCat(what, " are not finite"));
    }
  }
  for (double v :
       {motion.joint_speed_rad_s, motion.joint_acceleration_rad_s2, motion.linear_speed_m_s,
        motion.linear_acceleration_m_s2, gripper.grasp_settle_s, gripper.release_s}) {
    if (!std::isfinite(v)) return absl::InvalidArgumentError("a speed or wait is not finite");
  }
  auto pose = [](const Eigen::Isometry3d& T) { return ur::FormatPoseLiteral(ur::ToUrPose(T)); };
  const std::string transit_move =
      plan.transit ? absl::StrCat("  movej(", ur::FormatJointsLiteral(plan.transit_joints),
                                  ", a=", FormatNumber(motion.joint_acceleration_rad_s2),
                                  ", v=", FormatNumber(motion.joint_speed_rad_s), ")\n")
                   : std::string();
  const std::string text = absl::StrReplaceAll(
      kPickProgramTemplate,
      {
          {"${name}", name},
          {"${tcp_offset}", pose(gripper.flange_T_tcp)},
          {"${approach_joints}", ur::FormatJointsLiteral(plan.approach_joints)},
          {"${place_above_joints}", ur::FormatJointsLiteral(plan.place_above_joints)},
          {"${approach}", pose(plan.approach)},
          {"${grasp}", pose(plan.grasp)},
          {"${retrieve}", pose(plan.retrieve)},
          {"${transit_move}", transit_move},
          {"${place_above}", pose(plan.place_above)},
          {"${place}", pose(plan.place)},
          {"${clear_joints}", ur::FormatJointsLiteral(clear_joints)},
          {"${joint_speed}", FormatNumber(motion.joint_speed_rad_s)},
          {"${joint_acceleration}", FormatNumber(motion.joint_acceleration_rad_s2)},
          {"${linear_speed}", FormatNumber(motion.linear_speed_m_s)},
          {"${linear_acceleration}", FormatNumber(motion.linear_acceleration_m_s2)},
          {"${suction_out}", gripper.suction_output == SuctionOutputKind::kTool
                                 ? "set_tool_digital_out"
                                 : "set_standard_digital_out"},
          {"${suction_index}", absl::StrCat(gripper.suction_output_index)},
          {"${grasp_settle}", FormatNumber(gripper.grasp_settle_s)},
          {"${release}", FormatNumber(gripper.release_s)},
      });
  return text;
}

}  // namespace cornerpose::robot_client
