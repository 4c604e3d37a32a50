// ReadPcd (our PCD reader) against PCL's reader on files PCL writes: every
// encoding, fields in any order, colour as U and F, labels, COUNT > 1, NaN
// points of organized clouds. The same comparison runs on real files when
// their folders follow the test's flags:
//   pcd_reader_test --compare ../shared/data/real ../shared/data/dev
// Then the reader's own errors and the fuzzer's findings.
#include "common/io/pcd_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "common/io/cloud_io.h"

namespace cornerpose {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// x, y, z and the packed colour of PCL's blob, copied out the way PCL's own
// point types would see them.
struct PclPoints {
  uint32_t width = 0, height = 0;
  std::vector<Eigen::Vector3d> xyz;
  std::vector<uint32_t> rgb;
};

double PclValue(const uint8_t* p, uint8_t datatype) {
  auto load = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  switch (datatype) {
    case pcl::PCLPointField::INT8: return load(int8_t{});
    case pcl::PCLPointField::UINT8: return load(uint8_t{});
    case pcl::PCLPointField::INT16: return load(int16_t{});
    case pcl::PCLPointField::UINT16: return load(uint16_t{});
    case pcl::PCLPointField::INT32: return load(int32_t{});
    case pcl::PCLPointField::UINT32: return load(uint32_t{});
    case pcl::PCLPointField::FLOAT32: return load(float{});
    default: return load(double{});
  }
}

PclPoints ReadWithPcl(const std::string& path) {
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  EXPECT_EQ(reader.read(path, blob), 0) << path;
  PclPoints out;
  out.width = blob.width;
  out.height = blob.height;
  const pcl::PCLPointField* axes[3] = {nullptr, nullptr, nullptr};
  const pcl::PCLPointField* colour = nullptr;
  for (const pcl::PCLPointField& f : blob.fields) {
    for (int a = 0; a < 3; ++a) {
      if (axes[a] == nullptr && f.name == std::string(1, static_cast<char>('x' + a))) axes[a] = &f;
    }
    if (colour == nullptr && (f.name == "rgb" || f.name == "rgba") &&
        pcl::getFieldSize(f.datatype) == 4) {
      colour = &f;
    }
  }
  const size_t n = size_t{blob.width} * blob.height;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* point = blob.data.data() + i * blob.point_step;
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a) p[a] = PclValue(point + axes[a]->offset, axes[a]->datatype);
    out.xyz.push_back(p);
    if (colour != nullptr) {
      uint32_t packed;
      std::memcpy(&packed, point + colour->offset, 4);
      out.rgb.push_back(packed & 0x00FFFFFFu);
    }
  }
  return out;
}

// Exactly PCL's values: the same float in each axis, NaN in all three where
// PCL has any non-finite one, the same colour.
void ExpectSameAsPcl(const std::string& path) {
  SCOPED_TRACE(path);
  const PclPoints want = ReadWithPcl(path);
  const absl::StatusOr<PointCloud> got = ReadPcd(ReadBytes(path));
  ASSERT_TRUE(got.ok()) << got.status();
  ASSERT_EQ(got->size(), want.xyz.size());
  if (!want.xyz.empty()) {
    EXPECT_EQ(got->width, static_cast<int>(want.width));
    EXPECT_EQ(got->height, static_cast<int>(std::max<uint32_t>(want.height, 1)));
  }
  ASSERT_EQ(got->rgb.size(), want.rgb.size());
  int mismatches = 0;
  for (size_t i = 0; i < want.xyz.size() && mismatches < 5; ++i) {
    const Eigen::Vector3d& w = want.xyz[i];
    const Eigen::Vector3f& g = got->xyz[i];
    const bool same = w.allFinite() ? g == w.cast<float>() : g.array().isNaN().all();
    const bool same_rgb = want.rgb.empty() || got->rgb[i] == want.rgb[i];
    if (!same || !same_rgb) {
      ++mismatches;
      ADD_FAILURE() << "point " << i << ": PCL " << w.transpose() << " rgb "
                    << (want.rgb.empty() ? 0 : want.rgb[i]) << ", ours " << g.transpose()
                    << " rgb " << (got->rgb.empty() ? 0 : got->rgb[i]);
    }
  }
}

class PcdReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("pcd_reader_test_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

struct FieldSpec {
  std::string name;
  uint8_t datatype;
  uint32_t count = 1;
};

// A PCL blob with these fields, filled with varied values: coordinates in
// metres with NaN pixels, colours with every byte used, labels, normals.
pcl::PCLPointCloud2 MakeBlob(const std::vector<FieldSpec>& specs, uint32_t width,
                             uint32_t height) {
  pcl::PCLPointCloud2 blob;
  blob.width = width;
  blob.height = height;
  uint32_t offset = 0;
  for (const FieldSpec& s : specs) {
    pcl::PCLPointField f;
    f.name = s.name;
    f.datatype = s.datatype;
    f.count = s.count;
    f.offset = offset;
    offset += pcl::getFieldSize(s.datatype) * s.count;
    blob.fields.push_back(f);
  }
  blob.point_step = offset;
  blob.row_step = offset * width;
  blob.is_dense = false;
  blob.data.resize(size_t{blob.row_step} * height);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f);
  for (size_t i = 0; i < size_t{width} * height; ++i) {
    uint8_t* point = blob.data.data() + i * blob.point_step;
    const bool hole = height > 1 && i % 5 == 3;
    for (const pcl::PCLPointField& f : blob.fields) {
      for (uint32_t c = 0; c < f.count; ++c) {
        uint8_t* p = point + f.offset + c * pcl::getFieldSize(f.datatype);
        const bool axis = f.name == "x" || f.name == "y" || f.name == "z";
        if (f.name == "rgb" || f.name == "rgba") {
          const uint32_t packed = static_cast<uint32_t>(rng());
          std::memcpy(p, &packed, 4);  // the same bits whether U or F
        } else if (f.datatype == pcl::PCLPointField::FLOAT32) {
          const float v = axis && hole ? kNaN : coord(rng);
          std::memcpy(p, &v, 4);
        } else if (f.datatype == pcl::PCLPointField::FLOAT64) {
          const double v = axis && hole ? std::nan("") : coord(rng);
          std::memcpy(p, &v, 8);
        } else {
          const uint32_t v = static_cast<uint32_t>(rng()) & 0x7F;
          std::memcpy(p, &v, pcl::getFieldSize(f.datatype));
        }
      }
    }
  }
  return blob;
}

TEST_F(PcdReaderTest, MatchesPclOnEveryEncodingAndFieldLayout) {
  using F = pcl::PCLPointField;
  const std::vector<std::vector<FieldSpec>> layouts = {
      {{"x", F::FLOAT32}, {"y", F::FLOAT32}, {"z", F::FLOAT32}},
      // As the MOSD frames: a label first, rgba U.
      {{"label", F::UINT32}, {"x", F::FLOAT32}, {"y", F::FLOAT32}, {"z", F::FLOAT32},
       {"rgba", F::UINT32}},
      // As PCL's PointXYZRGB: rgb stored as F; then a label.
      {{"x", F::FLOAT32}, {"y", F::FLOAT32}, {"z", F::FLOAT32}, {"rgb", F::FLOAT32},
       {"label", F::UINT32}},
      // Reordered axes, a COUNT 3 field, doubles, small integers.
      {{"normal", F::FLOAT32, 3}, {"z", F::FLOAT64}, {"intensity", F::UINT8}, {"y", F::FLOAT32},
       {"x", F::FLOAT64}, {"ring", F::INT16}},
      // Integer coordinates.
      {{"x", F::INT16}, {"y", F::INT32}, {"z", F::UINT16}, {"rgb", F::UINT32}},
  };
  pcl::PCDWriter writer;
  int k = 0;
  for (const std::vector<FieldSpec>& layout : layouts) {
    for (const auto& [w, h] : {std::pair<uint32_t, uint32_t>{7, 5}, {23, 1}, {0, 1}}) {
      const pcl::PCLPointCloud2 blob = MakeBlob(layout, w, h);
      const std::string base = Path("cloud" + std::to_string(k++));
      ASSERT_EQ(writer.writeASCII(base + "_ascii.pcd", blob), 0);
      ASSERT_EQ(writer.writeBinary(base + "_binary.pcd", blob), 0);
      ExpectSameAsPcl(base + "_ascii.pcd");
      ExpectSameAsPcl(base + "_binary.pcd");
      if (w > 0) {  // PCL refuses to compress an empty cloud
        ASSERT_EQ(writer.writeBinaryCompressed(base + "_compressed.pcd", blob), 0);
        ExpectSameAsPcl(base + "_compressed.pcd");
      }
    }
  }
}

TEST_F(PcdReaderTest, ReadsAnAsciiFileWithoutVersionAndWithFloatColourBits) {
  // As the RGB-D object dataset: no VERSION line, rgb F written as a float.
  const float colour_bits = [] {
    const uint32_t packed = 0x00A0B0C0u;
    float f;
    std::memcpy(&f, &packed, 4);
    return f;
  }();
  char value[64];
  std::snprintf(value, sizeof value, "%.9g", colour_bits);
  const std::string text = std::string(
                               "FIELDS x y z rgb imX imY\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\n"
                               "COUNT 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                               "POINTS 2\nDATA ascii\n-0.5 0.25 1.5 ") +
                           value + " 298 199\n\n0 0 2 4294967295 1 2\n";
  const std::string path = Path("no_version.pcd");
  std::ofstream(path) << text;
  ExpectSameAsPcl(path);
  const absl::StatusOr<PointCloud> cloud = ReadPcd(text);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_EQ(cloud->xyz[0], Eigen::Vector3f(-0.5f, 0.25f, 1.5f));
  EXPECT_EQ(cloud->rgb[0], 0x00A0B0C0u);
  // An integer in an F field is a float too, as PCL reads it: 2^32 has the
  // bits 0x4F800000.
  EXPECT_EQ(cloud->rgb[1], 0x00800000u);
}

TEST_F(PcdReaderTest, SkipsPaddingFieldsInBinaryBodies) {
  std::string bytes =
      "VERSION 0.7\nFIELDS x _ y z\nSIZE 4 2 4 4\nTYPE F U F F\nCOUNT 1 3 1 1\nWIDTH 1\n"
      "HEIGHT 1\nPOINTS 1\nDATA binary\n";
  const float x = 1.5f, y = -2.0f, z = 3.25f;
  bytes.append(reinterpret_cast<const char*>(&x), 4);
  bytes.append(6, '\x7f');
  bytes.append(reinterpret_cast<const char*>(&y), 4);
  bytes.append(reinterpret_cast<const char*>(&z), 4);
  const absl::StatusOr<PointCloud> cloud = ReadPcd(bytes);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_EQ(cloud->xyz[0], Eigen::Vector3f(x, y, z));
  EXPECT_TRUE(cloud->rgb.empty());
}

const char kAsciiHeader[] =
    "VERSION 0.7\nFIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\n"
    "HEIGHT 1\nPOINTS 2\nDATA ascii\n";

TEST(PcdReaderErrorsTest, AsciiBodiesNameThePointTheFieldAndTheValue) {
  auto error = [](const std::string& body) {
    const absl::StatusOr<PointCloud> c = ReadPcd(kAsciiHeader + body);
    EXPECT_TRUE(absl::IsInvalidArgument(c.status())) << body;
    return std::string(c.status().message());
  };
  EXPECT_THAT(error("1 2 3 4\n1.0 2.0 3.0\n"), HasSubstr("point 1 has 3 values, expected 4"));
  EXPECT_THAT(error("1 2 3 4\n1 2 3 4 5\n"), HasSubstr("point 1 has 5 values, expected 4"));
  EXPECT_THAT(error("1 2 3 4\n1 abc 3 4\n"),
              HasSubstr("point 1: field 'y' value 'abc' is not a F4 number"));
  EXPECT_THAT(error("1 2 3 4\n1 2.5x 3 4\n"), HasSubstr("'2.5x'"));
  EXPECT_THAT(error("1 2 3 4\n1 2 3 4\n1 2 3 4\n"), HasSubstr("more than the 2 points"));
  // The body check (at least two characters a value) lets this one through
  // to the reader, which finds the second point missing.
  EXPECT_THAT(error("1 2 3 4444444444 \n"), HasSubstr("ends after 1 of 2 points"));
  const absl::StatusOr<PointCloud> ok = ReadPcd(std::string(kAsciiHeader) + "1 2 3 4\nnan NaN 3 4");
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_TRUE(ok->xyz[1].array().isNaN().all());
}

TEST(PcdReaderErrorsTest, IntegerCoordinatesMustFitTheirType) {
  const std::string header =
      "FIELDS x y z\nSIZE 1 2 4\nTYPE U I F\nWIDTH 1\nPOINTS 1\nDATA ascii\n";
  EXPECT_TRUE(ReadPcd(header + "255 -32768 1\n").ok());
  const absl::StatusOr<PointCloud> c = ReadPcd(header + "256 0 1\n");
  EXPECT_THAT(std::string(c.status().message()), HasSubstr("field 'x' value '256' is not a U1"));
  EXPECT_FALSE(ReadPcd(header + "1 -32769 1\n").ok());
  EXPECT_FALSE(ReadPcd(header + "1.5 0 1\n").ok());
}

TEST(PcdReaderErrorsTest, CompressedBlocksThatDoNotDecompressAreRefused) {
  std::string bytes =
      "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
      "DATA binary_compressed\n";
  // 24 bytes expanded from 6 bytes of LZF: a back reference before the start.
  const uint32_t sizes[2] = {6, 24};
  bytes.append(reinterpret_cast<const char*>(sizes), 8);
  bytes.append("\xe0\x10\x05\x00\x00\x00", 6);
  const absl::StatusOr<PointCloud> c = ReadPcd(bytes);
  EXPECT_TRUE(absl::IsInvalidArgument(c.status()));
  EXPECT_THAT(std::string(c.status().message()), HasSubstr("expected 24 (corrupt data)"));
}

TEST(PcdReaderErrorsTest, EmptyAndHeaderOnlyInputsAreRefused) {
  EXPECT_THAT(std::string(ReadPcd("").status().message()), HasSubstr("empty file"));
  EXPECT_THAT(std::string(ReadPcd("FIELDS x y z\n").status().message()), HasSubstr("no DATA"));
}

// pcd_fuzzer: a binary body after "DATA binary_compreay" (binary, by PCL's
// prefix rule) made PCL's reader fault; ours reads its 3 x 2 points.
TEST(PcdFuzzRegressionTest, MislabelledBinaryBodyReadsAsBinary) {
  const std::string path =
      std::string(CORNERPOSE_FUZZ_TEST_DATA) + "/pcd_binary_data_line_misspelt.pcd";
  ASSERT_TRUE(fs::exists(path));
  const absl::StatusOr<PointCloud> cloud = LoadPointCloud(path);
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_EQ(cloud->width, 3);
  EXPECT_EQ(cloud->height, 2);
  for (const Eigen::Vector3f& p : cloud->xyz) {
    EXPECT_TRUE(p.allFinite() || p.array().isNaN().all());
  }
}

// One file given after --compare, read by both readers.
class CompareWithPcl : public ::testing::Test {
 public:
  explicit CompareWithPcl(std::string path) : path_(std::move(path)) {}
  void TestBody() override { ExpectSameAsPcl(path_); }

 private:
  std::string path_;
};

}  // namespace
}  // namespace cornerpose

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  bool compare = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--compare") {
      compare = true;
      continue;
    }
    if (!compare) continue;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(argv[i])) {
      if (entry.path().extension() != ".pcd") continue;
      const std::string path = entry.path().string();
      ::testing::RegisterTest("PcdReaderCompareTest", path.c_str(), nullptr, nullptr, __FILE__,
                              __LINE__, [path] { return new cornerpose::CompareWithPcl(path); });
    }
  }
  return RUN_ALL_TESTS();
}
