#include "robot_client/ur/primary.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "robot_client/ur/byte_io.h"
#include "robot_client/ur/kinematics.h"
#include "tests/ur/test_data.h"

namespace cornerpose::ur {
namespace {

constexpr char kUr5e[] = "ur5e_ursim5.8_primary_robot_state.bin";
constexpr char kCb2[] = "ur5_cb2_secondary_robot_state_2013.bin";
constexpr char kKey[] = "primary_key_message_program_started_example.bin";
constexpr char kException[] = "primary_runtime_exception_message_example.bin";

template <typename T>
T ParseAs(const std::string& bytes) {
  absl::StatusOr<PrimaryPackage> p = ParsePrimaryPackage(bytes);
  EXPECT_TRUE(p.ok()) << p.status();
  if (!p.ok()) return T{};
  EXPECT_TRUE(std::holds_alternative<T>(*p)) << "variant index " << p->index();
  if (!std::holds_alternative<T>(*p)) return T{};
  return std::get<T>(*p);
}

TEST(PrimaryUr5e, DecodesRecordedUrsimState) {
  const std::string bytes = ReadTestFile(kUr5e);
  ASSERT_EQ(bytes.size(), 1386u);
  const RobotState s = ParseAs<RobotState>(bytes);
  EXPECT_EQ(s.order, (std::vector<uint8_t>{0, 1, 4, 5, 9, 3, 2, 6, 7, 8, 10, 11, 12}));
  EXPECT_EQ(s.other.size(), 9u);

  ASSERT_TRUE(s.robot_mode.has_value());
  const RobotModeData& m = *s.robot_mode;
  EXPECT_EQ(m.timestamp, 25643784000u);
  EXPECT_TRUE(m.real_robot_connected);
  EXPECT_TRUE(m.real_robot_enabled);
  EXPECT_TRUE(m.power_on);
  EXPECT_FALSE(m.emergency_stopped);
  EXPECT_FALSE(m.protective_stopped);
  EXPECT_FALSE(m.program_running);
  EXPECT_FALSE(m.program_paused);
  EXPECT_EQ(m.robot_mode, 7);
  EXPECT_EQ(m.control_mode, 0);
  EXPECT_EQ(m.target_speed_fraction, 0.97);
  EXPECT_EQ(m.speed_scaling, 0.0);
  EXPECT_EQ(m.target_speed_fraction_limit, 1.0);
  EXPECT_EQ(m.extra.size(), 1u);  // 47-byte 5.x layout

  ASSERT_TRUE(s.joints.has_value());
  const Joints q = {-1.6006999999999998, -1.7271, -2.2029999999999994,
                    -0.8079999999999998, 1.5951,  -0.030999999999999694};
  EXPECT_EQ(ActualJoints(*s.joints), q);
  EXPECT_EQ(TargetJoints(*s.joints), q);
  const float temperatures[6] = {25.5f, 25.0f, 24.5f, 24.0f, 23.5f, 23.5f};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(s.joints->joints[i].qd_actual, 0.0);
    EXPECT_EQ(s.joints->joints[i].mode, 253);
    EXPECT_EQ(s.joints->joints[i].motor_temperature, temperatures[i]);
  }
  EXPECT_TRUE(s.joints->extra.empty());

  ASSERT_TRUE(s.cartesian.has_value());
  EXPECT_EQ(s.cartesian->tcp_pose.position,
            Eigen::Vector3d(-0.14396865671352163, -0.43562006080319216, 0.2020300254283846));
  EXPECT_EQ(s.cartesian->tcp_pose.rotation,
            Eigen::Vector3d(-0.0012213596815925638, 3.1162765284819756, 0.038891915636886834));
  ASSERT_TRUE(s.cartesian->tcp_offset.has_value());
  EXPECT_EQ(s.cartesian->tcp_offset->position, Eigen::Vector3d::Zero());
  EXPECT_EQ(s.cartesian->tcp_offset->rotation, Eigen::Vector3d::Zero());

  ASSERT_TRUE(s.masterboard.has_value());
  EXPECT_FALSE(s.masterboard->io_words_16bit);
  EXPECT_EQ(s.masterboard->digital_input_bits, 0u);
  EXPECT_EQ(s.masterboard->digital_output_bits, 0u);
  EXPECT_EQ(s.masterboard->safety_mode, 1);
  EXPECT_EQ(s.masterboard->robot_voltage_48v, 48.0f);
  EXPECT_EQ(s.masterboard->extra.size(), 7u);  // 75-byte 5.x layout
}

TEST(PrimaryUr5e, ForwardKinematicsMatchesReportedPose) {
  const RobotState s = ParseAs<RobotState>(ReadTestFile(kUr5e));
  ASSERT_TRUE(s.joints && s.cartesian);
  const Eigen::Isometry3d fk = ForwardKinematics(ArmModel::kUr5e, ActualJoints(*s.joints));
  const Eigen::Isometry3d reported = FromUrPose(s.cartesian->tcp_pose);
  EXPECT_LT((fk.translation() - reported.translation()).norm(), 1e-9);
  EXPECT_LT(
      RotationAngleBetween(Eigen::Quaterniond(fk.linear()), Eigen::Quaterniond(reported.linear())),
      1e-9);
}

TEST(PrimaryUr5e, KinematicsInfoIsKeptRaw) {
  const RobotState s = ParseAs<RobotState>(ReadTestFile(kUr5e));
  const auto it = std::find_if(s.other.begin(), s.other.end(), [](const RawSubPackage& r) {
    return r.type == static_cast<uint8_t>(RobotStateType::kKinematicsInfo);
  });
  ASSERT_NE(it, s.other.end());
  // 6 uint32 checksums, then DH theta, a, d, alpha (URCL's layout): check d1.
  ByteReader r(it->body);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(*r.U32(), 4294967295u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(*r.Double(), 0.0);  // theta
  for (int i = 0; i < 6; ++i) EXPECT_EQ(*r.Double(), NominalDh(ArmModel::kUr5e).a[i]);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(*r.Double(), NominalDh(ArmModel::kUr5e).d[i]);
}

TEST(PrimaryCb2, DecodesCapturedControllerState) {
  const std::string bytes = ReadTestFile(kCb2);
  ASSERT_EQ(bytes.size(), 510u);
  const RobotState s = ParseAs<RobotState>(bytes);
  EXPECT_EQ(s.order, (std::vector<uint8_t>{0, 1, 4, 3, 2, 7, 8}));
  ASSERT_TRUE(s.robot_mode.has_value());
  EXPECT_EQ(s.robot_mode->timestamp, 57918u);
  EXPECT_TRUE(s.robot_mode->real_robot_connected);
  EXPECT_TRUE(s.robot_mode->real_robot_enabled);
  EXPECT_TRUE(s.robot_mode->power_on);
  EXPECT_FALSE(s.robot_mode->emergency_stopped);
  EXPECT_FALSE(s.robot_mode->protective_stopped);
  EXPECT_FALSE(s.robot_mode->program_running);
  EXPECT_FALSE(s.robot_mode->program_paused);
  EXPECT_EQ(s.robot_mode->robot_mode, 0);
  EXPECT_FALSE(s.robot_mode->control_mode.has_value());
  EXPECT_EQ(s.robot_mode->target_speed_fraction, 1.0);
  EXPECT_TRUE(s.robot_mode->extra.empty());

  ASSERT_TRUE(s.joints.has_value());
  EXPECT_EQ(ActualJoints(*s.joints),
            (Joints{-3.859885325398998, -2.262535292828023, 2.391686075850997, -1.9961094698395456,
                    2.8755209057205486, -2.082074328305076}));
  for (const JointState& j : s.joints->joints) {
    EXPECT_EQ(j.mode, 253);
    EXPECT_NEAR(j.voltage, 47.5, 0.5);
  }

  ASSERT_TRUE(s.cartesian.has_value());
  EXPECT_FALSE(s.cartesian->tcp_offset.has_value());
  EXPECT_EQ(s.cartesian->tcp_pose.position,
            Eigen::Vector3d(0.17079748121924124, -0.10959361590609135, 0.41373163491905257));
  EXPECT_EQ(s.cartesian->tcp_pose.rotation,
            Eigen::Vector3d(1.3065256631795277, -0.3989354110254162, -0.84890166395034));

  ASSERT_TRUE(s.masterboard.has_value());
  EXPECT_TRUE(s.masterboard->io_words_16bit);
  EXPECT_EQ(s.masterboard->digital_input_bits, 0u);
  EXPECT_EQ(s.masterboard->digital_output_bits, 0u);

  // Nominal UR5 FK: same rotation, position within the arm's calibration.
  const Eigen::Isometry3d fk = ForwardKinematics(ArmModel::kUr5, ActualJoints(*s.joints));
  EXPECT_LT((fk.translation() - s.cartesian->tcp_pose.position).norm(), 3e-3);
  EXPECT_LT(RotationAngleBetween(Eigen::Quaterniond(fk.linear()),
                                 QuaternionFromRotationVector(s.cartesian->tcp_pose.rotation)),
            1e-6);
}

TEST(PrimaryMessages, KeyExample) {
  const std::string bytes = ReadTestFile(kKey);
  const KeyMessage m = ParseAs<KeyMessage>(bytes);
  EXPECT_EQ(m.header.timestamp, 0u);
  EXPECT_EQ(m.header.source, -2);
  EXPECT_EQ(m.code, 0);
  EXPECT_EQ(m.argument, 0);
  EXPECT_EQ(m.title, "PROGRAM_XXX_STARTED");
  EXPECT_EQ(m.text, "textmsg");
  EXPECT_EQ(EncodeKeyMessage(m), bytes);
}

TEST(PrimaryMessages, RuntimeExceptionExample) {
  // The hand-assembled example's length field says 57, but its text runs to
  // 59 bytes: a strict parser must refuse it.
  std::string bytes = ReadTestFile(kException);
  ASSERT_EQ(bytes.size(), 59u);
  EXPECT_EQ(bytes.substr(0, 4), std::string("\x00\x00\x00\x39", 4));
  EXPECT_EQ(ParsePrimaryPackage(bytes).status().code(), absl::StatusCode::kInvalidArgument);
  bytes[3] = 59;
  const RuntimeExceptionMessage m = ParseAs<RuntimeExceptionMessage>(bytes);
  EXPECT_EQ(m.header.timestamp, 0u);
  EXPECT_EQ(m.header.source, -3);
  EXPECT_EQ(m.line, 3);
  EXPECT_EQ(m.column, 1);
  EXPECT_EQ(m.text, "compile_error_name_not_found:txtmsg:");
  EXPECT_EQ(EncodeRuntimeExceptionMessage(m), bytes);
}

TEST(PrimaryEncode, RecordedPackagesRoundTripByteExact) {
  for (const char* name : {kUr5e, kCb2, kKey}) {
    SCOPED_TRACE(name);
    const std::string bytes = ReadTestFile(name);
    absl::StatusOr<PrimaryPackage> p = ParsePrimaryPackage(bytes);
    ASSERT_TRUE(p.ok()) << p.status();
    EXPECT_EQ(EncodePrimaryPackage(*p), bytes);
  }
}

TEST(PrimaryEncode, MessagesRoundTrip) {
  VersionMessage v;
  v.header.timestamp = 123;
  v.header.source = -2;
  v.project_name = "URControl";
  v.major = 5;
  v.minor = 8;
  v.bugfix = 2;
  v.build = 10833;
  v.build_date = "25-08-2020, 13:31:38";
  const VersionMessage v2 = ParseAs<VersionMessage>(EncodeVersionMessage(v));
  EXPECT_EQ(v2.project_name, "URControl");
  EXPECT_EQ(v2.major, 5);
  EXPECT_EQ(v2.minor, 8);
  EXPECT_EQ(v2.bugfix, 2);
  EXPECT_EQ(v2.build, 10833);
  EXPECT_EQ(v2.build_date, v.build_date);
  EXPECT_EQ(EncodeVersionMessage(v2), EncodeVersionMessage(v));

  TextMessage t;
  t.text = "still running";
  EXPECT_EQ(ParseAs<TextMessage>(EncodeTextMessage(t)).text, "still running");

  SafetyModeMessage s;
  s.code = 209;
  s.safety_mode = 3;
  s.report_data_type = 4;
  s.report_data = 0xdeadbeef;
  const std::string sb = EncodeSafetyModeMessage(s);
  EXPECT_EQ(sb.size(), 5u + 10u + 17u);
  const SafetyModeMessage s2 = ParseAs<SafetyModeMessage>(sb);
  EXPECT_EQ(s2.code, 209);
  EXPECT_EQ(s2.safety_mode, 3);
  EXPECT_EQ(s2.report_data, 0xdeadbeef);

  ErrorCodeMessage e;
  e.code = 210;
  e.report_level = 2;
  e.text = "read only";
  const ErrorCodeMessage e2 = ParseAs<ErrorCodeMessage>(EncodeErrorCodeMessage(e));
  EXPECT_EQ(e2.code, 210);
  EXPECT_EQ(e2.report_level, 2);
  EXPECT_EQ(e2.text, "read only");

  const std::string label = EncodePrimaryPackage(
      OtherRobotMessage{.header = {}, .message_type = 1, .body = std::string("\x00\x01xy", 4)});
  const OtherRobotMessage o = ParseAs<OtherRobotMessage>(label);
  EXPECT_EQ(o.message_type, 1);
  EXPECT_EQ(EncodePrimaryPackage(o), label);
  const std::string program_state = EncodePrimaryPackage(OtherPackage{.type = 25, .body = "abc"});
  EXPECT_EQ(ParseAs<OtherPackage>(program_state).body, "abc");
}

TEST(PrimaryEncode, DefaultStateHasThe5xLayout) {
  RobotState s;
  s.robot_mode.emplace();
  s.joints.emplace();
  s.cartesian.emplace();
  s.masterboard.emplace();
  s.robot_mode->protective_stopped = true;
  s.joints->joints[2].q_actual = 1.25;
  s.masterboard->digital_output_bits = 0x5;
  const std::string bytes = EncodeRobotState(s);
  EXPECT_EQ(bytes.size(), 5u + 47u + 251u + 101u + 75u);
  // The recorded 5.x packet's sub-package headers, same lengths.
  EXPECT_EQ(bytes.substr(5, 5), std::string("\x00\x00\x00\x2f\x00", 5));
  EXPECT_EQ(bytes.substr(52, 5), std::string("\x00\x00\x00\xfb\x01", 5));
  EXPECT_EQ(bytes.substr(303, 5), std::string("\x00\x00\x00\x65\x04", 5));
  EXPECT_EQ(bytes.substr(404, 5), std::string("\x00\x00\x00\x4b\x03", 5));
  const RobotState back = ParseAs<RobotState>(bytes);
  ASSERT_TRUE(back.robot_mode && back.joints && back.masterboard);
  EXPECT_TRUE(back.robot_mode->protective_stopped);
  EXPECT_EQ(back.joints->joints[2].q_actual, 1.25);
  EXPECT_EQ(back.masterboard->digital_output_bits, 0x5u);
  EXPECT_EQ(EncodeRobotState(back), bytes);
}

TEST(PrimaryParse, TruncatedAndGarbageNeverCrash) {
  for (const char* name : {kUr5e, kCb2, kKey, kException}) {
    SCOPED_TRACE(name);
    const std::string bytes = ReadTestFile(name);
    for (size_t n = 0; n < bytes.size(); ++n) {
      const std::string prefix = bytes.substr(0, n);
      // Length field no longer matches (the exception example's says 57).
      if (n != 57 || name != std::string(kException)) {
        EXPECT_FALSE(ParsePrimaryPackage(prefix).ok()) << n;
      }
      if (n < 5) continue;
      // Length field patched to the prefix: the body is cut short.
      ByteWriter w;
      w.PutI32(static_cast<int32_t>(n));
      std::string patched = w.data() + prefix.substr(4);
      absl::StatusOr<PrimaryPackage> p = ParsePrimaryPackage(patched);
      if (name == std::string(kUr5e)) {
        // Cut inside a sub-package is an error; at a boundary, fewer of them.
        const std::set<size_t> boundaries = {5,   52,   303,  404,  629,  682, 757,
                                             794, 1239, 1300, 1309, 1352, 1378};
        EXPECT_EQ(p.ok(), boundaries.count(n) > 0) << n << " " << p.status();
      }
    }
  }
  std::mt19937 rng(5);
  for (int i = 0; i < 2000; ++i) {
    std::string junk(5 + rng() % 300, '\0');
    for (char& c : junk) c = static_cast<char>(rng());
    ByteWriter w;
    w.PutI32(static_cast<int32_t>(junk.size()));
    junk.replace(0, 4, w.data());
    junk[4] = static_cast<char>(std::array<uint8_t, 4>{16, 20, 25, 99}[i % 4]);
    (void)ParsePrimaryPackage(junk);  // any result, no crash
  }
}

TEST(PrimaryParse, BadSubPackageLengthIsAnError) {
  std::string bytes = ReadTestFile(kUr5e);
  bytes[8] = 0x7f;  // first sub-package length huge
  const absl::StatusOr<PrimaryPackage> p = ParsePrimaryPackage(bytes);
  ASSERT_FALSE(p.ok());
  EXPECT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument);
  std::string zero = ReadTestFile(kUr5e);
  zero[5] = zero[6] = zero[7] = zero[8] = 0;  // length 0 would loop forever
  EXPECT_FALSE(ParsePrimaryPackage(zero).ok());
}

TEST(PrimaryFramer, SplitsAStreamReadByteByByte) {
  const std::string stream = ReadTestFile(kUr5e) + ReadTestFile(kKey) + ReadTestFile(kCb2);
  PrimaryFramer framer;
  std::vector<std::string> frames;
  for (char c : stream) {
    framer.Append(std::string(1, c));
    absl::StatusOr<std::optional<std::string>> f = framer.Next();
    ASSERT_TRUE(f.ok()) << f.status();
    if (f->has_value()) frames.push_back(**f);
  }
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0], ReadTestFile(kUr5e));
  EXPECT_EQ(frames[1], ReadTestFile(kKey));
  EXPECT_EQ(frames[2], ReadTestFile(kCb2));
  EXPECT_EQ(framer.buffered(), 0u);

  PrimaryFramer bad;
  bad.Append(std::string("\x00\x00\x00\x02\x10", 5));
  EXPECT_EQ(bad.Next().status().code(), absl::StatusCode::kDataLoss);
}

}  // namespace
}  // namespace cornerpose::ur
