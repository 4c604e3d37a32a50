#include "common/io/cloud_io.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace cornerpose {
namespace {

namespace fs = std::filesystem;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

class CloudIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("cloud_io_test_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));  // concurrent runs from other build dirs
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  static void WriteBytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  static std::string ReadBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  fs::path dir_;
};

// A 4 x 3 organized cloud with two NaN pixels.
pcl::PointCloud<pcl::PointXYZ> OrganizedPclCloud() {
  pcl::PointCloud<pcl::PointXYZ> cloud(4, 3);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 4; ++u) {
      cloud.at(u, v) = pcl::PointXYZ(0.1f * u - 0.15f, 0.1f * v - 0.1f, 1.0f + 0.01f * (u + v));
    }
  }
  cloud.at(1, 1) = pcl::PointXYZ(kNaN, kNaN, kNaN);
  cloud.at(3, 2) = pcl::PointXYZ(kNaN, kNaN, kNaN);
  cloud.is_dense = false;
  return cloud;
}

void ExpectSameAsPcl(const PointCloud& got, const pcl::PointCloud<pcl::PointXYZ>& want) {
  ASSERT_EQ(got.width, static_cast<int>(want.width));
  ASSERT_EQ(got.height, static_cast<int>(want.height));
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    const pcl::PointXYZ& w = want[i];
    if (!std::isfinite(w.z)) {
      EXPECT_TRUE(std::isnan(got.xyz[i].x()) && std::isnan(got.xyz[i].y()) &&
                  std::isnan(got.xyz[i].z()))
          << "point " << i;
      continue;
    }
    EXPECT_NEAR(got.xyz[i].x(), w.x, 1e-6f) << "point " << i;
    EXPECT_NEAR(got.xyz[i].y(), w.y, 1e-6f) << "point " << i;
    EXPECT_NEAR(got.xyz[i].z(), w.z, 1e-6f) << "point " << i;
  }
}

TEST_F(CloudIoTest, ReadsPcdWrittenByPclInEveryEncoding) {
  const pcl::PointCloud<pcl::PointXYZ> cloud = OrganizedPclCloud();
  pcl::PCDWriter writer;
  ASSERT_EQ(writer.writeASCII(Path("ascii.pcd"), cloud), 0);
  ASSERT_EQ(writer.writeBinary(Path("binary.pcd"), cloud), 0);
  ASSERT_EQ(writer.writeBinaryCompressed(Path("compressed.pcd"), cloud), 0);
  for (const char* name : {"ascii.pcd", "binary.pcd", "compressed.pcd"}) {
    SCOPED_TRACE(name);
    absl::StatusOr<PointCloud> got = LoadPointCloud(Path(name));
    ASSERT_TRUE(got.ok()) << got.status();
    EXPECT_TRUE(got->organized());
    EXPECT_TRUE(got->Validate().ok());
    ExpectSameAsPcl(*got, cloud);
  }
}

TEST_F(CloudIoTest, ReadsPcdWithExtraFieldsInAnotherOrder) {
  // Like the MOSD files: label first, then x y z, then a colour; binary,
  // compressed and organized.
  pcl::PointCloud<pcl::PointXYZRGBL> cloud(3, 2);
  for (size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = 0.5f + i;
    cloud[i].y = -0.25f * i;
    cloud[i].z = 2.0f + 0.125f * i;
    cloud[i].label = static_cast<uint32_t>(7 * i);
    cloud[i].rgba = 0xff102030u;
  }
  cloud[4].x = cloud[4].y = cloud[4].z = kNaN;
  pcl::PCDWriter writer;
  ASSERT_EQ(writer.writeBinaryCompressed(Path("rgbl.pcd"), cloud), 0);
  absl::StatusOr<PointCloud> got = LoadPointCloud(Path("rgbl.pcd"));
  ASSERT_TRUE(got.ok()) << got.status();
  ASSERT_EQ(got->width, 3);
  ASSERT_EQ(got->height, 2);
  EXPECT_FLOAT_EQ(got->xyz[5].x(), 5.5f);
  EXPECT_FLOAT_EQ(got->xyz[5].y(), -1.25f);
  EXPECT_FLOAT_EQ(got->xyz[5].z(), 2.625f);
  EXPECT_FALSE(PointCloud::IsValid(got->xyz[4]));
}

TEST_F(CloudIoTest, ReadsHandWrittenAsciiPcdWithReorderedFieldsAndNoVersion) {
  WriteBytes(Path("hand.PCD"),
             "# .PCD v.7 - hand written, no VERSION line\n"
             "FIELDS label x y z rgba\n"
             "SIZE 4 4 4 4 4\n"
             "TYPE U F F F U\n"
             "COUNT 1 1 1 1 1\n"
             "WIDTH 3\n"
             "HEIGHT 1\n"
             "VIEWPOINT 0 0 0 1 0 0 0\n"
             "POINTS 3\n"
             "DATA ascii\n"
             "5 0.1 0.2 0.3 4278190080\n"
             "6 -1.5 2.5 3.5 0\n"
             "7 nan nan nan 0\n");
  absl::StatusOr<PointCloud> got = LoadPointCloud(Path("hand.PCD"));
  ASSERT_TRUE(got.ok()) << got.status();
  ASSERT_EQ(got->size(), 3u);
  EXPECT_EQ(got->height, 1);
  EXPECT_FALSE(got->organized());
  EXPECT_TRUE(got->xyz[0].isApprox(Eigen::Vector3f(0.1f, 0.2f, 0.3f)));
  EXPECT_TRUE(got->xyz[1].isApprox(Eigen::Vector3f(-1.5f, 2.5f, 3.5f)));
  EXPECT_FALSE(PointCloud::IsValid(got->xyz[2]));
}

TEST_F(CloudIoTest, SavePcdRoundTripsAndPclReadsIt) {
  PointCloud cloud;
  cloud.width = 4;
  cloud.height = 3;
  for (int i = 0; i < 12; ++i) cloud.xyz.emplace_back(0.001f * i, -0.5f * i, 1.0f + i);
  cloud.xyz[5] = Eigen::Vector3f::Constant(kNaN);
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    const std::string path = Path(binary ? "b.pcd" : "a.pcd");
    ASSERT_TRUE(SavePcd(path, cloud, binary).ok());
    absl::StatusOr<PointCloud> got = LoadPointCloud(path);
    ASSERT_TRUE(got.ok()) << got.status();
    ASSERT_EQ(got->width, 4);
    ASSERT_EQ(got->height, 3);
    for (int i = 0; i < 12; ++i) {
      if (i == 5) {
        EXPECT_FALSE(PointCloud::IsValid(got->xyz[i]));
      } else {
        EXPECT_EQ(got->xyz[i], cloud.xyz[i]) << i;  // %.9g is exact for floats
      }
    }
    pcl::PointCloud<pcl::PointXYZ> pcl_cloud;
    ASSERT_EQ(pcl::io::loadPCDFile(path, pcl_cloud), 0);
    EXPECT_EQ(pcl_cloud.width, 4u);
    EXPECT_EQ(pcl_cloud.height, 3u);
    EXPECT_FLOAT_EQ(pcl_cloud.at(3, 2).z, 12.0f);
  }
}

TEST_F(CloudIoTest, SavePointsWritesUnorganizedCloudIncludingEmpty) {
  const std::vector<Eigen::Vector3f> points = {{1, 2, 3}, {4, 5, 6}};
  ASSERT_TRUE(SavePoints(Path("edges.pcd"), points).ok());
  absl::StatusOr<PointCloud> got = LoadPointCloud(Path("edges.pcd"));
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->width, 2);
  EXPECT_EQ(got->height, 1);
  EXPECT_EQ(got->xyz, points);

  ASSERT_TRUE(SavePoints(Path("none.pcd"), {}).ok());
  absl::StatusOr<PointCloud> empty = LoadPointCloud(Path("none.pcd"));
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_TRUE(empty->empty());
  EXPECT_TRUE(empty->Validate().ok());
}

TEST_F(CloudIoTest, ReadsPlyWrittenByPcl) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 10; ++i) cloud.push_back(pcl::PointXYZ(0.1f * i, 1.0f - i, 2.0f + i));
  pcl::PLYWriter writer;
  ASSERT_EQ(writer.write(Path("b.ply"), cloud, /*binary=*/true), 0);
  ASSERT_EQ(writer.write(Path("a.ply"), cloud, /*binary=*/false), 0);
  for (const char* name : {"b.ply", "a.ply"}) {
    SCOPED_TRACE(name);
    absl::StatusOr<PointCloud> got = LoadPointCloud(Path(name));
    ASSERT_TRUE(got.ok()) << got.status();
    ExpectSameAsPcl(*got, cloud);
  }
}

TEST_F(CloudIoTest, ReadsOrganizedPly) {
  // PCL keeps the grid either in a camera element (viewport size, all points
  // written) or in a range_grid element (NaN points left out).
  const pcl::PointCloud<pcl::PointXYZ> cloud = OrganizedPclCloud();
  pcl::PLYWriter writer;
  for (bool binary : {true, false}) {
    for (bool use_camera : {true, false}) {
      SCOPED_TRACE(::testing::Message() << "binary " << binary << " camera " << use_camera);
      ASSERT_EQ(writer.write(Path("org.ply"), cloud, binary, use_camera), 0);
      if (!use_camera) {
        ASSERT_NE(ReadBytes(Path("org.ply")).find("element range_grid 12"), std::string::npos);
      }
      absl::StatusOr<PointCloud> got = LoadPointCloud(Path("org.ply"));
      ASSERT_TRUE(got.ok()) << got.status();
      ExpectSameAsPcl(*got, cloud);
    }
  }
}

TEST_F(CloudIoTest, DepthPngRoundTripsAndBecomesACloud) {
  const int w = 5, h = 4;
  std::vector<uint16_t> depth(w * h);
  for (int i = 0; i < w * h; ++i) depth[i] = static_cast<uint16_t>(1000 + 37 * i);
  depth[7] = 0;
  depth[18] = 65534;  // the largest depth, 65.534 m
  depth[19] = 65535;  // no return on some stereo cameras
  ASSERT_TRUE(WriteDepthPng(Path("d.png"), depth, w, h).ok());
  int rw = 0, rh = 0;
  absl::StatusOr<std::vector<uint16_t>> back = ReadDepthPng(Path("d.png"), &rw, &rh);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(rw, w);
  EXPECT_EQ(rh, h);
  EXPECT_EQ(*back, depth);

  CameraIntrinsics camera{w, h, 10.0, 12.0, 2.0, 1.5};
  absl::StatusOr<PointCloud> cloud = LoadPointCloud(Path("d.png"), {.intrinsics = camera});
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->width, w);
  ASSERT_EQ(cloud->height, h);
  EXPECT_FALSE(PointCloud::IsValid(cloud->xyz[7]));
  const int u = 3, v = 2, i = v * w + u;
  const double z = depth[i] * 0.001;
  EXPECT_NEAR(cloud->xyz[i].z(), z, 1e-6);
  EXPECT_NEAR(cloud->xyz[i].x(), (u - 2.0) * z / 10.0, 1e-6);
  EXPECT_NEAR(cloud->xyz[i].y(), (v - 1.5) * z / 12.0, 1e-6);
  EXPECT_NEAR(cloud->xyz[18].z(), 65.534, 1e-4);
  EXPECT_FALSE(PointCloud::IsValid(cloud->xyz[19]));

  absl::StatusOr<PointCloud> scaled =
      LoadPointCloud(Path("d.png"), {.intrinsics = camera, .depth_scale_m = 0.0001});
  ASSERT_TRUE(scaled.ok());
  EXPECT_NEAR(scaled->xyz[i].z(), z / 10, 1e-6);
}

TEST_F(CloudIoTest, DepthToCloudRejectsSizeMismatch) {
  CameraIntrinsics camera{4, 4, 10, 10, 2, 2};
  EXPECT_TRUE(DepthToCloud(std::vector<uint16_t>(15, 1000), camera, 0.001).empty());
  EXPECT_EQ(DepthToCloud(std::vector<uint16_t>(16, 1000), camera, 0.001).size(), 16u);
}

TEST_F(CloudIoTest, MissingFileIsNotFound) {
  for (const char* name : {"nope.pcd", "nope.ply", "nope.png", "nope.xyz"}) {
    EXPECT_EQ(LoadPointCloud(Path(name)).status().code(), absl::StatusCode::kNotFound) << name;
  }
  int w, h;
  EXPECT_EQ(ReadDepthPng(Path("nope.png"), &w, &h).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(CloudIoTest, GarbageAndEmptyFilesAreInvalid) {
  std::mt19937 rng(7);
  std::string garbage(5000, '\0');
  for (char& c : garbage) c = static_cast<char>(rng());
  for (const char* name : {"g.pcd", "g.ply", "g.png"}) {
    WriteBytes(Path(name), garbage);
    absl::StatusOr<PointCloud> got = LoadPointCloud(Path(name), {.intrinsics = CameraIntrinsics{}});
    EXPECT_EQ(got.status().code(), absl::StatusCode::kInvalidArgument) << name;
    EXPECT_NE(got.status().message().find(name), std::string::npos) << got.status();
  }
  for (const char* name : {"e.pcd", "e.ply", "e.png"}) {
    WriteBytes(Path(name), "");
    EXPECT_EQ(LoadPointCloud(Path(name), {.intrinsics = CameraIntrinsics{}}).status().code(),
              absl::StatusCode::kInvalidArgument)
        << name;
  }
  WriteBytes(Path("text.pcd"), "hello\nworld\n");
  EXPECT_EQ(LoadPointCloud(Path("text.pcd")).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(CloudIoTest, TruncatedBinaryDataIsInvalid) {
  const pcl::PointCloud<pcl::PointXYZ> cloud = OrganizedPclCloud();
  pcl::PCDWriter writer;
  ASSERT_EQ(writer.writeBinary(Path("full.pcd"), cloud), 0);
  ASSERT_EQ(writer.writeBinaryCompressed(Path("fullc.pcd"), cloud), 0);
  pcl::PLYWriter ply;
  ASSERT_EQ(ply.write(Path("full.ply"), cloud, /*binary=*/true), 0);
  for (const char* name : {"full.pcd", "fullc.pcd", "full.ply"}) {
    const std::string bytes = ReadBytes(Path(name));
    const std::string cut = std::string("cut_") + name;
    WriteBytes(Path(cut), bytes.substr(0, bytes.size() - 20));
    EXPECT_EQ(LoadPointCloud(Path(cut)).status().code(), absl::StatusCode::kInvalidArgument)
        << name;
  }
}

TEST_F(CloudIoTest, HeadersAnnouncingMoreThanTheFileHoldsAreInvalid) {
  // Without the header checks PCL would try to allocate these.
  WriteBytes(Path("huge.pcd"),
             "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2000000000\nHEIGHT 1\n"
             "POINTS 2000000000\nDATA ascii\n1 2 3\n");
  WriteBytes(Path("negative.pcd"),
             "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH -1\nHEIGHT 1\n"
             "POINTS -1\nDATA binary\n");
  WriteBytes(Path("huge.ply"),
             "ply\nformat ascii 1.0\nobj_info num_cols 100000\nobj_info num_rows 100000\n"
             "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
             "end_header\n1 2 3\n");
  WriteBytes(Path("huge2.ply"),
             "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
             "property float x\nproperty float y\nproperty float z\nend_header\n");
  WriteBytes(Path("noxyz.pcd"),
             "FIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
             "POINTS 1\nDATA ascii\n1 2 3\n");
  WriteBytes(Path("shortline.pcd"),
             "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
             "POINTS 3\nDATA ascii\n1 2 3\n4 5\n6 7 8\n");
  // Layouts that PCL's PLY reader aborts on (assert) or silently misreads.
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  WriteBytes(Path("small_grid.ply"),
             "ply\nformat ascii 1.0\nobj_info num_cols 1\n"
             "obj_info num_rows 1\nelement vertex 3\n" +
                 xyz + "end_header\n1 2 3\n4 5 6\n7 8 9\n");
  WriteBytes(Path("alpha.ply"), "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz +
                                    "property uchar alpha\nend_header\n1 2 3 4\n");
  WriteBytes(Path("blue.ply"), "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz +
                                   "property uchar blue\nend_header\n1 2 3 4\n1 2 3 4\n");
  WriteBytes(Path("list.ply"), "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz +
                                   "property list uchar float w\nend_header\n"
                                   "1 2 3 1 5\n1 2 3 3 5 6 7\n");
  for (const char* name :
       {"huge.pcd", "negative.pcd", "huge.ply", "huge2.ply", "noxyz.pcd", "shortline.pcd",
        "small_grid.ply", "alpha.ply", "blue.ply", "list.ply"}) {
    EXPECT_EQ(LoadPointCloud(Path(name)).status().code(), absl::StatusCode::kInvalidArgument)
        << name;
  }
}

TEST_F(CloudIoTest, DepthPngErrors) {
  // An 8-bit RGB PNG is not a depth image.
  ASSERT_TRUE(WriteRgbPng(Path("rgb.png"), std::vector<uint8_t>(4 * 3 * 3, 100), 4, 3).ok());
  absl::StatusOr<PointCloud> rgb =
      LoadPointCloud(Path("rgb.png"), {.intrinsics = CameraIntrinsics{4, 3, 5, 5, 2, 1}});
  EXPECT_EQ(rgb.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(rgb.status().message().find("16-bit"), std::string::npos) << rgb.status();

  ASSERT_TRUE(WriteDepthPng(Path("d.png"), std::vector<uint16_t>(12, 800), 4, 3).ok());
  absl::StatusOr<PointCloud> no_camera = LoadPointCloud(Path("d.png"));
  EXPECT_EQ(no_camera.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(no_camera.status().message().find("intrinsics"), std::string::npos);
  EXPECT_EQ(LoadPointCloud(Path("d.png"), {.intrinsics = CameraIntrinsics{}}).status().code(),
            absl::StatusCode::kInvalidArgument);  // 640 x 480 != 4 x 3
  EXPECT_EQ(LoadPointCloud(Path("d.png"),
                           {.intrinsics = CameraIntrinsics{4, 3, 5, 5, 2, 1}, .depth_scale_m = 0})
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);

  // A PNG cut short.
  const std::string bytes = ReadBytes(Path("d.png"));
  WriteBytes(Path("cut.png"), bytes.substr(0, bytes.size() / 2));
  EXPECT_EQ(LoadPointCloud(Path("cut.png"), {.intrinsics = CameraIntrinsics{4, 3, 5, 5, 2, 1}})
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_F(CloudIoTest, UnknownExtensionIsInvalid) {
  WriteBytes(Path("cloud.xyz"), "1 2 3\n");
  EXPECT_EQ(LoadPointCloud(Path("cloud.xyz")).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(LoadPointCloud(dir_.string()).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(CloudIoTest, WritingToAnUnwritablePathFails) {
  const std::string bad = Path("no_such_dir/x");
  EXPECT_FALSE(SavePcd(bad + ".pcd", PointCloud{}).ok());
  EXPECT_FALSE(SavePoints(bad + ".pcd", {}).ok());
  EXPECT_FALSE(WriteDepthPng(bad + ".png", std::vector<uint16_t>(4), 2, 2).ok());
  EXPECT_FALSE(WriteDepthPng(Path("x.png"), std::vector<uint16_t>(3), 2, 2).ok());
  PointCloud broken;
  broken.width = 3;
  broken.height = 3;
  EXPECT_EQ(SavePcd(Path("broken.pcd"), broken).code(), absl::StatusCode::kInvalidArgument);
}

// Truncations and byte flips of valid files must give OK or INVALID_ARGUMENT,
// never a crash, a hang or an exception.
TEST_F(CloudIoTest, MutatedFilesNeverCrash) {
  const pcl::PointCloud<pcl::PointXYZ> cloud = OrganizedPclCloud();
  pcl::PCDWriter writer;
  ASSERT_EQ(writer.writeASCII(Path("m_a.pcd"), cloud), 0);
  ASSERT_EQ(writer.writeBinary(Path("m_b.pcd"), cloud), 0);
  ASSERT_EQ(writer.writeBinaryCompressed(Path("m_c.pcd"), cloud), 0);
  pcl::PLYWriter ply;
  ASSERT_EQ(ply.write(Path("m_b.ply"), cloud, true), 0);
  ASSERT_EQ(ply.write(Path("m_a.ply"), cloud, false), 0);
  ASSERT_TRUE(WriteDepthPng(Path("m_d.png"), std::vector<uint16_t>(12, 900), 4, 3).ok());
  const LoadOptions options{.intrinsics = CameraIntrinsics{4, 3, 5, 5, 2, 1}};
  std::mt19937 rng(11);
  int ok = 0, invalid = 0;
  for (const char* name : {"m_a.pcd", "m_b.pcd", "m_c.pcd", "m_b.ply", "m_a.ply", "m_d.png"}) {
    const std::string bytes = ReadBytes(Path(name));
    const std::string ext = fs::path(name).extension().string();
    for (int trial = 0; trial < 150; ++trial) {
      std::string mutated = bytes;
      if (trial % 3 == 0) {
        mutated.resize(rng() % bytes.size());
      } else {
        const int flips = 1 + static_cast<int>(rng() % 4);
        for (int k = 0; k < flips; ++k) {
          mutated[rng() % mutated.size()] = static_cast<char>(rng());
        }
      }
      const std::string path = Path("mutant" + ext);
      WriteBytes(path, mutated);
      absl::StatusOr<PointCloud> got = LoadPointCloud(path, options);
      if (got.ok()) {
        ++ok;
        EXPECT_TRUE(got->Validate().ok()) << name << " trial " << trial;
      } else {
        ++invalid;
        EXPECT_EQ(got.status().code(), absl::StatusCode::kInvalidArgument)
            << name << " trial " << trial << ": " << got.status();
      }
    }
  }
  EXPECT_GT(invalid, 0);
  EXPECT_GT(ok, 0);
}

TEST(ParseIntrinsicsTest, AcceptsFourOrSixValues) {
  absl::StatusOr<CameraIntrinsics> four = ParseIntrinsics("525, 526,319.5,239.5");
  ASSERT_TRUE(four.ok()) << four.status();
  EXPECT_EQ(four->width, 640);
  EXPECT_EQ(four->height, 480);
  EXPECT_EQ(four->fx, 525);
  EXPECT_EQ(four->fy, 526);
  EXPECT_EQ(four->cx, 319.5);
  EXPECT_EQ(four->cy, 239.5);
  absl::StatusOr<CameraIntrinsics> six = ParseIntrinsics("1280,720,900,900,640,360");
  ASSERT_TRUE(six.ok()) << six.status();
  EXPECT_EQ(six->width, 1280);
  EXPECT_EQ(six->height, 720);
  EXPECT_EQ(six->fx, 900);
  EXPECT_EQ(six->cy, 360);
}

TEST(ParseIntrinsicsTest, RejectsMalformedText) {
  for (const char* text :
       {"", "525,525,319.5", "a,b,c,d", "525,525,319.5,239.5,1", "640.5,480,525,525,319.5,239.5",
        "0,480,525,525,319.5,239.5", "-525,525,319.5,239.5", "525,525,nan,239.5"}) {
    absl::StatusOr<CameraIntrinsics> got = ParseIntrinsics(text);
    EXPECT_EQ(got.status().code(), absl::StatusCode::kInvalidArgument) << "'" << text << "'";
  }
}

}  // namespace
}  // namespace cornerpose
