#include "robot_client/ur/rtde.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/ur/test_data.h"

namespace cornerpose::ur {
namespace {

std::string Bytes(std::initializer_list<int> b) {
  std::string out;
  for (int c : b) out.push_back(static_cast<char>(c));
  return out;
}

// ur-interface.md section 2.3, byte-exact examples (URCL tests).
TEST(RtdeHandshake, ByteExactExamples) {
  EXPECT_EQ(EncodeRequestProtocolVersion(2), Bytes({0x00, 0x05, 0x56, 0x00, 0x02}));
  EXPECT_EQ(EncodeAccepted(RtdeMessageType::kRequestProtocolVersion, true),
            Bytes({0x00, 0x04, 0x56, 0x01}));
  EXPECT_EQ(EncodeGetUrcontrolVersion(), Bytes({0x00, 0x03, 0x76}));
  EXPECT_EQ(EncodeStart(), Bytes({0x00, 0x03, 0x53}));
  EXPECT_EQ(EncodeAccepted(RtdeMessageType::kStart, true), Bytes({0x00, 0x04, 0x53, 0x01}));
  EXPECT_EQ(EncodePause(), Bytes({0x00, 0x03, 0x50}));
  EXPECT_EQ(EncodeAccepted(RtdeMessageType::kPause, true), Bytes({0x00, 0x04, 0x50, 0x01}));

  const std::string setup = EncodeSetupOutputs({500.0, {"actual_q", "actual_qd"}});
  EXPECT_EQ(setup,
            Bytes({0x00, 0x1d, 0x4f, 0x40, 0x7f, 0x40, 0, 0, 0, 0, 0}) + "actual_q,actual_qd");
  EXPECT_EQ(EncodeSetupReply(RtdeMessageType::kSetupOutputs, {1, {"VECTOR6D", "VECTOR6D"}}),
            Bytes({0x00, 0x15, 0x4f, 0x01}) + "VECTOR6D,VECTOR6D");

  // Client -> controller: input recipe 1, speed_slider_mask = 1.
  EXPECT_EQ(EncodeDataPackage({1, {uint32_t{1}}}),
            Bytes({0x00, 0x08, 0x55, 0x01, 0x00, 0x00, 0x00, 0x01}));
}

TEST(RtdeHandshake, ParsesBothDirections) {
  absl::StatusOr<RtdeFrame> f = ParseRtdeFrame(EncodeRequestProtocolVersion());
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->type, 'V');
  EXPECT_EQ(*ParseRequestProtocolVersion(f->payload), 2);
  EXPECT_TRUE(*ParseAccepted(std::string(1, '\1')));
  EXPECT_FALSE(*ParseAccepted(std::string(1, '\0')));
  EXPECT_FALSE(ParseAccepted("").ok());

  f = ParseRtdeFrame(EncodeSetupOutputs({125.0, {"timestamp", "actual_q"}}));
  ASSERT_TRUE(f.ok());
  absl::StatusOr<SetupOutputsRequest> request = ParseSetupOutputs(f->payload);
  ASSERT_TRUE(request.ok());
  EXPECT_EQ(request->frequency, 125.0);
  EXPECT_EQ(request->names, (std::vector<std::string>{"timestamp", "actual_q"}));

  f = ParseRtdeFrame(EncodeSetupInputs({"speed_slider_mask", "input_int_register_24"}));
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->type, 'I');
  EXPECT_EQ(ParseSetupInputs(f->payload),
            (std::vector<std::string>{"speed_slider_mask", "input_int_register_24"}));

  absl::StatusOr<SetupReply> reply = ParseSetupReply(Bytes({0x01}) + "DOUBLE,VECTOR6D");
  ASSERT_TRUE(reply.ok());
  EXPECT_EQ(reply->recipe_id, 1);
  absl::StatusOr<std::vector<RtdeType>> types = RecipeTypes(*reply, {"timestamp", "actual_q"});
  ASSERT_TRUE(types.ok()) << types.status();
  EXPECT_EQ(*types, (std::vector<RtdeType>{RtdeType::kDouble, RtdeType::kVector6d}));

  const absl::StatusOr<std::vector<RtdeType>> refused =
      RecipeTypes({0, {"DOUBLE", "NOT_FOUND"}}, {"timestamp", "no_such_thing"});
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(refused.status().message().find("no_such_thing"), std::string::npos);
  EXPECT_EQ(RecipeTypes({1, {"IN_USE"}}, {"speed_slider_mask"}).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST(RtdeRecorded, UrcontrolVersionReply) {
  const std::string bytes = ReadTestFile("rtde_urcontrol_version_reply_5.8.bin");
  absl::StatusOr<RtdeFrame> f = ParseRtdeFrame(bytes);
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_EQ(f->type, 'v');
  absl::StatusOr<UrcontrolVersion> v = ParseUrcontrolVersion(f->payload);
  ASSERT_TRUE(v.ok());
  EXPECT_EQ(v->major, 5u);
  EXPECT_EQ(v->minor, 8u);
  EXPECT_EQ(v->bugfix, 0u);
  EXPECT_EQ(v->build, 0u);
  EXPECT_EQ(EncodeUrcontrolVersion(*v), bytes);
}

TEST(RtdeRecorded, DataPackageTimestampTargetSpeedFraction) {
  const std::string bytes =
      ReadTestFile("rtde_data_package_frame_timestamp_target_speed_fraction.bin");
  ASSERT_EQ(bytes.size(), 20u);
  absl::StatusOr<RtdeFrame> f = ParseRtdeFrame(bytes);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->type, 'U');
  const std::vector<RtdeType> types = {*RtdeOutputType("timestamp"),
                                       *RtdeOutputType("target_speed_fraction")};
  absl::StatusOr<RtdeDataPackage> p = ParseDataPackage(f->payload, types);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_EQ(p->recipe_id, 1);
  EXPECT_EQ(std::get<double>(p->values[0]), 16412.206);
  EXPECT_EQ(std::get<double>(p->values[1]), 1.0);
  EXPECT_EQ(EncodeDataPackage(*p), bytes);
}

TEST(RtdeRecorded, DataPayloadTimestampActualQ) {
  const std::string payload = ReadTestFile("rtde_data_payload_timestamp_actual_q.bin");
  ASSERT_EQ(payload.size(), 57u);
  absl::StatusOr<RtdeDataPackage> p =
      ParseDataPackage(payload, {RtdeType::kDouble, RtdeType::kVector6d});
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_EQ(p->recipe_id, 1);
  EXPECT_NEAR(std::get<double>(p->values[0]), 16854.192, 1e-3);
  const auto q = std::get<std::array<double, 6>>(p->values[1]);
  EXPECT_EQ(q,
            (std::array<double, 6>{-1.6007002035724085, -1.7271001974688929, -2.2029998938189905,
                                   -0.8079999128924769, 1.5951000452041626, -0.03099996248354131}));
  EXPECT_EQ(EncodeDataPackage(*p), std::string("\x00\x3c\x55", 3) + payload);
  // The wrong recipe: size mismatch is an error.
  EXPECT_FALSE(ParseDataPackage(payload, {RtdeType::kDouble}).ok());
  EXPECT_FALSE(
      ParseDataPackage(payload.substr(0, 40), {RtdeType::kDouble, RtdeType::kVector6d}).ok());
}

TEST(RtdeTypes, TableAndSizes) {
  EXPECT_EQ(RtdeOutputType("timestamp"), RtdeType::kDouble);
  EXPECT_EQ(RtdeOutputType("actual_TCP_pose"), RtdeType::kVector6d);
  EXPECT_EQ(RtdeOutputType("actual_digital_output_bits"), RtdeType::kUint64);
  EXPECT_EQ(RtdeOutputType("robot_mode"), RtdeType::kInt32);
  EXPECT_EQ(RtdeOutputType("safety_status_bits"), RtdeType::kUint32);
  EXPECT_EQ(RtdeOutputType("runtime_state"), RtdeType::kUint32);
  EXPECT_EQ(RtdeOutputType("joint_mode"), RtdeType::kVector6Int32);
  EXPECT_EQ(RtdeOutputType("output_double_register_47"), RtdeType::kDouble);
  EXPECT_EQ(RtdeOutputType("output_int_register_48"), std::nullopt);
  EXPECT_EQ(RtdeOutputType("output_int_register_07"), std::nullopt);
  EXPECT_EQ(RtdeOutputType("actual_q "), std::nullopt);
  EXPECT_EQ(RtdeInputType("speed_slider_mask"), RtdeType::kUint32);
  EXPECT_EQ(RtdeInputType("input_int_register_24"), RtdeType::kInt32);
  EXPECT_EQ(RtdeInputType("standard_digital_output"), RtdeType::kUint8);
  for (RtdeType t : {RtdeType::kBool, RtdeType::kUint8, RtdeType::kUint32, RtdeType::kUint64,
                     RtdeType::kInt32, RtdeType::kDouble, RtdeType::kVector3d, RtdeType::kVector6d,
                     RtdeType::kVector6Int32, RtdeType::kVector6Uint32}) {
    EXPECT_EQ(*ParseRtdeTypeName(RtdeTypeName(t)), t);
  }
  EXPECT_EQ(RtdeTypeSize(RtdeType::kVector6Int32), 24u);
  EXPECT_EQ(RtdeTypeSize(RtdeType::kVector6d), 48u);
  EXPECT_EQ(ParseRtdeTypeName("FLOAT").status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(RtdeData, EveryTypeRoundTrips) {
  RtdeDataPackage p;
  p.recipe_id = 7;
  p.values = {true,
              uint8_t{200},
              uint32_t{4000000000u},
              uint64_t{1ULL << 63},
              int32_t{-5},
              3.25,
              std::array<double, 3>{1, 2, 3},
              std::array<double, 6>{1, 2, 3, 4, 5, 6},
              std::array<int32_t, 6>{-1, 2, -3, 4, -5, 253},
              std::array<uint32_t, 6>{1, 2, 3, 4, 5, 4000000000u}};
  std::vector<RtdeType> types;
  for (const RtdeValue& v : p.values) types.push_back(TypeOf(v));
  const std::string frame = EncodeDataPackage(p);
  EXPECT_EQ(frame.size(), 3u + 1u + 1 + 1 + 4 + 8 + 4 + 8 + 24 + 48 + 24 + 24);
  absl::StatusOr<RtdeFrame> f = ParseRtdeFrame(frame);
  ASSERT_TRUE(f.ok());
  absl::StatusOr<RtdeDataPackage> back = ParseDataPackage(f->payload, types);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->recipe_id, 7);
  EXPECT_EQ(back->values, p.values);
}

TEST(RtdeText, RoundTrip) {
  const std::string frame = EncodeRtdeTextMessage({"hello", "RTDE", 2});
  absl::StatusOr<RtdeFrame> f = ParseRtdeFrame(frame);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->type, 'M');
  absl::StatusOr<RtdeTextMessage> m = ParseRtdeTextMessage(f->payload);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->message, "hello");
  EXPECT_EQ(m->source, "RTDE");
  EXPECT_EQ(m->level, 2);
  EXPECT_FALSE(ParseRtdeTextMessage(f->payload.substr(0, 4)).ok());
}

TEST(RtdeFramer, StreamAndGarbage) {
  const std::string stream = EncodeRequestProtocolVersion() + EncodeStart() +
                             ReadTestFile("rtde_urcontrol_version_reply_5.8.bin");
  RtdeFramer framer;
  std::vector<uint8_t> types;
  for (char c : stream) {
    framer.Append(std::string(1, c));
    absl::StatusOr<std::optional<RtdeFrame>> f = framer.Next();
    ASSERT_TRUE(f.ok());
    if (f->has_value()) types.push_back((*f)->type);
  }
  EXPECT_EQ(types, (std::vector<uint8_t>{'V', 'S', 'v'}));
  RtdeFramer bad;
  bad.Append(Bytes({0x00, 0x02, 0x55}));
  EXPECT_EQ(bad.Next().status().code(), absl::StatusCode::kDataLoss);
  EXPECT_FALSE(ParseRtdeFrame(Bytes({0x00, 0x05, 0x56, 0x00})).ok());
  EXPECT_FALSE(ParseRtdeFrame(Bytes({0x00})).ok());

  std::mt19937 rng(9);
  for (int i = 0; i < 2000; ++i) {
    std::string junk(rng() % 64, '\0');
    for (char& c : junk) c = static_cast<char>(rng());
    (void)ParseDataPackage(junk, {RtdeType::kDouble, RtdeType::kVector6d});
    (void)ParseRtdeTextMessage(junk);
    (void)ParseSetupReply(junk);
    (void)ParseUrcontrolVersion(junk);
  }
}

}  // namespace
}  // namespace cornerpose::ur
