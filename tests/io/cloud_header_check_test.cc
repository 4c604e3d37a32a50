// The phases of CheckPcdHeader (common/io/cloud_header_check.h) one by one,
// and the whole check on files.
#include "common/io/cloud_header_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace cornerpose::internal {
namespace {

using ::testing::HasSubstr;

std::string Message(const absl::Status& s) { return std::string(s.message()); }

constexpr char kHeader[] =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z _ rgb\nSIZE 4 4 4 1 4\nTYPE F F F U U\n"
    "COUNT 1 1 1 3 1\nWIDTH 3\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA binary\n";

TEST(ParsePcdHeaderTest, ReadsFieldsCountsAndWhereTheBodyStarts) {
  const std::string text = std::string(kHeader) + "BODY";
  const absl::StatusOr<PcdHeader> h = ParsePcdHeader(text);
  ASSERT_TRUE(h.ok()) << h.status();
  ASSERT_EQ(h->fields.size(), 5u);
  EXPECT_EQ(h->fields[3].name, "_");
  EXPECT_EQ(h->fields[3].size, 1u);
  EXPECT_EQ(h->fields[3].count, 3u);
  EXPECT_EQ(h->fields[4].type, 'U');
  EXPECT_EQ(h->width, 3u);
  EXPECT_EQ(h->height, 2u);
  EXPECT_EQ(h->points, 6u);
  EXPECT_EQ(h->data, PcdData::kBinary);
  EXPECT_EQ(text.substr(h->data_offset), "BODY");
}

TEST(ParsePcdHeaderTest, DataKindsAsPclReadsThem) {
  for (const auto& [word, kind] : {std::pair{"ascii", PcdData::kAscii},
                                   std::pair{"binary", PcdData::kBinary},
                                   std::pair{"binary_compressed", PcdData::kBinaryCompressed},
                                   std::pair{"anything", PcdData::kAscii}}) {
    const absl::StatusOr<PcdHeader> h =
        ParsePcdHeader(std::string("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 0\nDATA ") + word + "\n");
    ASSERT_TRUE(h.ok()) << h.status();
    EXPECT_EQ(h->data, kind) << word;
  }
}

TEST(ParsePcdHeaderTest, RejectsLinesOutOfOrderOrOutOfRange) {
  const struct {
    const char* text;
    const char* error;
  } cases[] = {
      {"FIELDS x y z\nSIZE 4 4\nDATA ascii\n", "'SIZE' has 2 entries for 3 FIELDS"},
      {"SIZE 4 4 4\nDATA ascii\n", "entries for 0 FIELDS"},
      {"FIELDS x y z\nTYPE F F F\nDATA ascii\n", "TYPE comes before SIZE"},
      {"FIELDS x y z\nSIZE 4 4 4\nCOUNT 1 1 1\nDATA ascii\n", "COUNT comes before SIZE or TYPE"},
      {"FIELDS x y z\nSIZE 4 0 4\nDATA ascii\n", "SIZE entry '0' is not valid"},
      {"FIELDS x y z\nSIZE 4 4 4\nTYPE F FF F\nDATA ascii\n", "TYPE entries must be F, I or U"},
      {"FIELDS x y z\nWIDTH 2147483648\nDATA ascii\n", "has no valid count"},
      {"FIELDS x y z\nPOINTS -1\nDATA ascii\n", "has no valid count"},
      {"FIELDS x y z\nDATA\n", "DATA line names no format"},
      {"FIELDS x y z\nPOINTS 1\n", "no DATA line"},
      {"ply\nformat ascii 1.0\n", "unexpected header line 'ply'"},
  };
  for (const auto& c : cases) {
    const absl::StatusOr<PcdHeader> h = ParsePcdHeader(c.text);
    EXPECT_EQ(h.status().code(), absl::StatusCode::kInvalidArgument) << c.text;
    EXPECT_THAT(Message(h.status()), HasSubstr(c.error)) << c.text;
  }
}

TEST(PcdPointLayoutTest, StepsCountPaddingOnlyWhereItIsStored) {
  const absl::StatusOr<PcdHeader> h = ParsePcdHeader(kHeader);
  ASSERT_TRUE(h.ok());
  const absl::StatusOr<PcdLayout> layout = PcdPointLayout(h->fields);
  ASSERT_TRUE(layout.ok()) << layout.status();
  EXPECT_EQ(layout->point_step, 4u * 3 + 1 * 3 + 4);
  EXPECT_EQ(layout->packed_step, 4u * 3 + 4);
  EXPECT_EQ(layout->values_per_point, 3u + 3 + 1);
}

TEST(PcdPointLayoutTest, RejectsUnsupportedTypesAndMissingAxes) {
  std::vector<PcdField> fields = {{"x"}, {"y"}, {"z"}};
  EXPECT_TRUE(PcdPointLayout(fields).ok());
  fields[1].size = 2;  // half floats
  EXPECT_THAT(Message(PcdPointLayout(fields).status()),
              HasSubstr("field 'y' has unsupported type F of size 2"));
  fields[1] = {"y", 8, 'I', 1};  // 64-bit integers
  EXPECT_THAT(Message(PcdPointLayout(fields).status()), HasSubstr("unsupported type I of size 8"));
  fields = {{"x"}, {"y"}, {"normal_z"}};
  EXPECT_THAT(Message(PcdPointLayout(fields).status()), HasSubstr("no x, y and z fields"));
}

TEST(PcdPointCountTest, MissingSizesMeanOneRowAsInPcl) {
  PcdHeader h;
  EXPECT_THAT(Message(PcdPointCount(h).status()), HasSubstr("no POINTS line"));
  h.points = 12;
  EXPECT_EQ(*PcdPointCount(h), 12u);  // no WIDTH, no HEIGHT
  h.width = 12;
  EXPECT_EQ(*PcdPointCount(h), 12u);  // no HEIGHT
  h.width = 4;
  h.height = 3;
  EXPECT_EQ(*PcdPointCount(h), 12u);
  h.height = 4;
  EXPECT_THAT(Message(PcdPointCount(h).status()),
              HasSubstr("WIDTH x HEIGHT = 4 x 4 but POINTS is 12"));
}

std::string CompressedSizes(uint32_t compressed, uint32_t uncompressed) {
  std::string bytes(8, '\0');
  std::memcpy(bytes.data(), &compressed, 4);
  std::memcpy(bytes.data() + 4, &uncompressed, 4);
  return bytes;
}

TEST(CheckPcdBodySizeTest, BinaryAndAsciiBodiesMustHoldTheAnnouncedPoints) {
  const PcdLayout xyz{12, 12, 3};
  EXPECT_TRUE(CheckPcdBodySize(PcdData::kBinary, xyz, 10, 120, "").ok());
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kBinary, xyz, 10, 119, "")),
              HasSubstr("binary body holds 119 bytes, 120 expected"));
  // "0 0 0\n" per point at the least; the last newline may be missing.
  EXPECT_TRUE(CheckPcdBodySize(PcdData::kAscii, xyz, 10, 59, "").ok());
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kAscii, xyz, 10, 58, "")),
              HasSubstr("ascii body of 58 bytes is too short for 10 points"));
  // Beyond what PCL's 32-bit sizes can index, whatever the file holds.
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kBinary, xyz, 1u << 30, uint64_t{1} << 40, "")),
              HasSubstr("too many"));
}

TEST(CheckPcdBodySizeTest, CompressedBlockSizesMustMatchThePointsAndTheFile) {
  const PcdLayout padded{16, 12, 4};  // 4 bytes of "_" not stored compressed
  EXPECT_TRUE(CheckPcdBodySize(PcdData::kBinaryCompressed, padded, 0, 0, "").ok());
  EXPECT_TRUE(
      CheckPcdBodySize(PcdData::kBinaryCompressed, padded, 10, 108, CompressedSizes(100, 120))
          .ok());
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kBinaryCompressed, padded, 10, 7, "1234567")),
              HasSubstr("binary_compressed body is truncated"));
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kBinaryCompressed, padded, 10, 107,
                                       CompressedSizes(100, 120))),
              HasSubstr("compressed block of 100 bytes but only 99"));
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kBinaryCompressed, padded, 10, 108,
                                       CompressedSizes(100, 160))),
              HasSubstr("expands to 160 bytes, which does not match 10 points"));
  // More than LZF can expand: 120 000 bytes from 10.
  const PcdLayout xyz{12, 12, 3};
  EXPECT_THAT(Message(CheckPcdBodySize(PcdData::kBinaryCompressed, xyz, 10000, 18,
                                       CompressedSizes(10, 120000))),
              HasSubstr("expands to 120000 bytes"));
}

// pcd_fuzzer: FIELDS without SIZE and TYPE lines made PCL's ascii reader
// write outside the cloud.
TEST(ParsePcdHeaderTest, RejectsFieldsWithoutSizeAndType) {
  EXPECT_THAT(Message(ParsePcdHeader("FIELDS x y z\nPOINTS 1\nDATA ascii\n").status()),
              HasSubstr("no SIZE and TYPE lines"));
  const absl::Status s = cornerpose::CheckPcdHeader(std::string(CORNERPOSE_FUZZ_TEST_DATA) +
                                                    "/pcd_fields_without_size_and_type.pcd");
  EXPECT_THAT(Message(s), HasSubstr("no SIZE and TYPE lines"));
}

// pcd_fuzzer: header lines after DATA, which PCL obeys; a FIELDS line there
// made PCL's reader fault.
TEST(ParsePcdHeaderTest, RejectsHeaderLinesAfterData) {
  EXPECT_THAT(Message(ParsePcdHeader("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n# c\nFIELDS x\n0 0 0\n")
                          .status()),
              HasSubstr("PCD header line 'FIELDS x' after DATA"));
  EXPECT_TRUE(ParsePcdHeader("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n0 0 0\nFIELDS\n").ok());
  const std::string input =
      std::string(CORNERPOSE_FUZZ_TEST_DATA) + "/pcd_header_lines_after_data.pcd";
  const absl::Status s = cornerpose::CheckPcdHeader(input);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr("after DATA"));
}

TEST(CheckPcdHeaderTest, NamesTheFileAndPassesAGoodOne) {
  const std::string dir = ::testing::TempDir();
  const std::string good = dir + "/header_check_good.pcd";
  const std::string bad = dir + "/header_check_short.pcd";
  const std::string header =
      "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
      "DATA binary\n";
  std::ofstream(good, std::ios::binary) << header << std::string(24, '\0');
  std::ofstream(bad, std::ios::binary) << header << std::string(23, '\0');
  EXPECT_TRUE(cornerpose::CheckPcdHeader(good).ok()) << cornerpose::CheckPcdHeader(good);
  const absl::Status s = cornerpose::CheckPcdHeader(bad);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(Message(s), HasSubstr(bad + ": PCD binary body holds 23 bytes, 24 expected"));
  std::filesystem::remove(good);
  std::filesystem::remove(bad);
}

}  // namespace
}  // namespace cornerpose::internal
