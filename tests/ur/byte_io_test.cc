#include "robot_client/ur/byte_io.h"

#include <gtest/gtest.h>

namespace cornerpose::ur {
namespace {

TEST(ByteWriter, BigEndian) {
  ByteWriter w;
  w.PutU8(0x01);
  w.PutI8(-2);
  w.PutU16(0x0203);
  w.PutI32(-1);
  w.PutU32(0x04050607);
  w.PutU64(0x08090a0b0c0d0e0fULL);
  w.PutDouble(500.0);
  w.PutFloat(48.0f);
  w.PutBytes("ab");
  EXPECT_EQ(w.data(), std::string("\x01\xfe\x02\x03\xff\xff\xff\xff\x04\x05\x06\x07"
                                  "\x08\x09\x0a\x0b\x0c\x0d\x0e\x0f"
                                  "\x40\x7f\x40\x00\x00\x00\x00\x00"
                                  "\x42\x40\x00\x00"
                                  "ab",
                                  34));
  w.PatchU16(2, 0xbeef);
  w.PatchI32(4, 7);
  EXPECT_EQ(w.data().substr(2, 6), std::string("\xbe\xef\x00\x00\x00\x07", 6));
}

TEST(ByteReader, ReadsWhatWriterWrote) {
  ByteWriter w;
  w.PutU8(200);
  w.PutI8(-3);
  w.PutU16(65000);
  w.PutI32(-123456);
  w.PutU32(4000000000u);
  w.PutU64(1ULL << 60);
  w.PutDouble(-1.6006999999999998);
  w.PutFloat(25.5f);
  ByteReader r(w.data());
  EXPECT_EQ(*r.U8(), 200);
  EXPECT_EQ(*r.I8(), -3);
  EXPECT_EQ(*r.U16(), 65000);
  EXPECT_EQ(*r.I32(), -123456);
  EXPECT_EQ(*r.U32(), 4000000000u);
  EXPECT_EQ(*r.U64(), 1ULL << 60);
  EXPECT_EQ(*r.Double(), -1.6006999999999998);
  EXPECT_EQ(*r.Float(), 25.5f);
  EXPECT_TRUE(r.empty());
}

TEST(ByteReader, TruncationIsAnErrorAndDoesNotMove) {
  const std::string three("\x01\x02\x03", 3);
  ByteReader r(three);
  const absl::StatusOr<uint32_t> v = r.U32("length");
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_NE(v.status().message().find("length"), std::string::npos);
  EXPECT_EQ(r.position(), 0u);
  EXPECT_EQ(*r.U16(), 0x0102);
  EXPECT_FALSE(r.Double().ok());
  EXPECT_FALSE(r.Bytes(2).ok());
  EXPECT_FALSE(r.Skip(2).ok());
  EXPECT_EQ(r.Rest(), "\x03");
}

TEST(ByteReader, StickyErrors) {
  const std::string five("\x00\x00\x00\x2a\x07", 5);
  ByteReader r(five);
  EXPECT_EQ(r.GetI32(), 42);
  EXPECT_EQ(r.GetU32("second"), 0u);  // fails
  EXPECT_EQ(r.GetU8(), 0);            // still failing: sticky
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("second"), std::string::npos);
  EXPECT_EQ(r.GetBytes(1), "");
}

}  // namespace
}  // namespace cornerpose::ur
