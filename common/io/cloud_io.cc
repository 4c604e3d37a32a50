#include "common/io/cloud_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "common/io/cloud_header_check.h"
#include "common/io/pcd_reader.h"

namespace cornerpose {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// The header check bounds the points at 4 GiB; the header and slack on top.
constexpr uint64_t kMaxPcdFileBytes = (uint64_t{1} << 32) + (uint64_t{1} << 24);

// Byte size of a PCLPointField datatype, 0 when unsupported.
size_t FieldBytes(uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8:
    case pcl::PCLPointField::UINT8:
      return 1;
    case pcl::PCLPointField::INT16:
    case pcl::PCLPointField::UINT16:
      return 2;
    case pcl::PCLPointField::INT32:
    case pcl::PCLPointField::UINT32:
    case pcl::PCLPointField::FLOAT32:
      return 4;
    case pcl::PCLPointField::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

template <typename T>
double Load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return static_cast<double>(v);
}

double ReadValue(const uint8_t* p, uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8:
      return Load<int8_t>(p);
    case pcl::PCLPointField::UINT8:
      return Load<uint8_t>(p);
    case pcl::PCLPointField::INT16:
      return Load<int16_t>(p);
    case pcl::PCLPointField::UINT16:
      return Load<uint16_t>(p);
    case pcl::PCLPointField::INT32:
      return Load<int32_t>(p);
    case pcl::PCLPointField::UINT32:
      return Load<uint32_t>(p);
    case pcl::PCLPointField::FLOAT32:
      return Load<float>(p);
    default:
      return Load<double>(p);
  }
}

// Copies x, y, z out of a PCL blob, whatever their order, type and the other
// fields; checks every size against the buffer rather than trusting it.
absl::StatusOr<PointCloud> FromBlob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const pcl::PCLPointField* xyz[3] = {nullptr, nullptr, nullptr};
  for (const pcl::PCLPointField& f : blob.fields) {
    for (int axis = 0; axis < 3; ++axis) {
      if (xyz[axis] == nullptr && f.name == std::string(1, static_cast<char>('x' + axis))) {
        xyz[axis] = &f;
      }
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    const pcl::PCLPointField* f = xyz[axis];
    if (f == nullptr) return absl::InvalidArgumentError(absl::StrCat(path, ": no x, y, z fields"));
    const size_t bytes = FieldBytes(f->datatype);
    if (bytes == 0 || size_t{f->offset} + bytes > blob.point_step) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": field ", f->name, " has an unsupported type or offset"));
    }
  }
  const uint64_t n = uint64_t{blob.width} * blob.height;
  if (n > static_cast<uint64_t>(std::numeric_limits<int>::max()) ||
      n * blob.point_step > blob.data.size()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", blob.width, " x ", blob.height,
                                                   " points do not fit in ", blob.data.size(),
                                                   " bytes of data"));
  }
  // Colour: a 4-byte rgb or rgba field, U (uint32) or F (the same bits in a
  // float), packed 0xAARRGGBB; the alpha byte is dropped.
  const pcl::PCLPointField* colour = nullptr;
  for (const pcl::PCLPointField& f : blob.fields) {
    if ((f.name == "rgb" || f.name == "rgba") && FieldBytes(f.datatype) == 4 &&
        f.datatype != pcl::PCLPointField::INT8 && size_t{f.offset} + 4 <= blob.point_step) {
      colour = &f;
      break;
    }
  }
  PointCloud cloud;
  if (n == 0) return cloud;
  cloud.width = static_cast<int>(blob.width);
  cloud.height = static_cast<int>(std::max<uint32_t>(blob.height, 1));
  cloud.xyz.resize(static_cast<size_t>(n));
  for (size_t i = 0; i < cloud.xyz.size(); ++i) {
    const uint8_t* point = blob.data.data() + i * blob.point_step;
    Eigen::Vector3f p;
    for (int axis = 0; axis < 3; ++axis) {
      p[axis] = static_cast<float>(ReadValue(point + xyz[axis]->offset, xyz[axis]->datatype));
    }
    cloud.xyz[i] = p.allFinite() ? p : Eigen::Vector3f::Constant(kNaN);
  }
  if (colour != nullptr) {
    cloud.rgb.resize(cloud.xyz.size());
    for (size_t i = 0; i < cloud.rgb.size(); ++i) {
      uint32_t packed;
      std::memcpy(&packed, blob.data.data() + i * blob.point_step + colour->offset, 4);
      cloud.rgb[i] = packed & 0x00FFFFFFu;
    }
  }
  return cloud;
}

// Our own reader (pcd_reader.h), not PCL's: PCL's trusts the file's bytes.
absl::StatusOr<PointCloud> LoadPcd(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return absl::InvalidArgumentError(absl::StrCat(path, ": ", ec.message()));
  if (size > kMaxPcdFileBytes) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": ", size, " bytes is more than a PCD file may hold"));
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes(static_cast<size_t>(size), '\0');
  if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot read the file"));
  }
  absl::StatusOr<PointCloud> cloud = ReadPcd(bytes);
  if (!cloud.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", cloud.status().message()));
  }
  return cloud;
}

absl::StatusOr<PointCloud> LoadPly(const std::string& path) {
  if (absl::Status s = CheckPlyHeader(path); !s.ok()) return s;
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0;
  pcl::PLYReader reader;
  if (reader.read(path, blob, origin, orientation, version, 0) < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": PCL could not read this PLY file (corrupt or truncated data)"));
  }
  return FromBlob(blob, path);
}

absl::StatusOr<PointCloud> LoadDepthImage(const std::string& path, const LoadOptions& options) {
  if (!options.intrinsics) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": a depth image needs camera intrinsics to become a cloud"));
  }
  const CameraIntrinsics& camera = *options.intrinsics;
  if (absl::Status s = camera.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", s.message()));
  }
  if (!(options.depth_scale_m > 0.0) || !std::isfinite(options.depth_scale_m)) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": depth scale ", options.depth_scale_m, " m must be positive"));
  }
  int width = 0, height = 0;
  absl::StatusOr<std::vector<uint16_t>> depth = ReadDepthPng(path, &width, &height);
  if (!depth.ok()) return depth.status();
  if (width != camera.width || height != camera.height) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": depth image is ", width, " x ", height,
                                                   " but the intrinsics are for ", camera.width,
                                                   " x ", camera.height));
  }
  PointCloud cloud = DepthToCloud(*depth, camera, options.depth_scale_m);
  // A colour image registered to the depth image: NAME.color.png beside
  // NAME.png (the recorded-frame convention), used when it is there.
  if (!options.color_path && options.color_from_beside) {
    const std::filesystem::path p(path);
    const std::filesystem::path beside = p.parent_path() / (p.stem().string() + ".color.png");
    std::error_code ec;
    if (std::filesystem::is_regular_file(beside, ec)) {
      if (absl::Status s = AttachColor(beside.string(), &cloud); !s.ok()) return s;
    }
  }
  return cloud;
}

struct FileCloser {
  void operator()(FILE* f) const {
    if (f != nullptr) std::fclose(f);
  }
};

absl::StatusOr<PointCloud> LoadCloudFile(const std::string& path, const LoadOptions& options);

}  // namespace

absl::StatusOr<PointCloud> LoadPointCloud(const std::string& path, const LoadOptions& options) {
  absl::StatusOr<PointCloud> cloud = LoadCloudFile(path, options);
  if (!cloud.ok() || !options.color_path) return cloud;
  if (absl::Status s = AttachColor(*options.color_path, &*cloud); !s.ok()) return s;
  return cloud;
}

absl::Status AttachColor(const std::string& path, PointCloud* cloud) {
  if (!cloud->organized()) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": a colour image needs an organized cloud to register to"));
  }
  int width = 0, height = 0;
  absl::StatusOr<std::vector<uint8_t>> rgb = ReadRgbPng(path, &width, &height);
  if (!rgb.ok()) return rgb.status();
  if (width != cloud->width || height != cloud->height) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": colour image is ", width, " x ", height,
                                                   " but the cloud is ", cloud->width, " x ",
                                                   cloud->height));
  }
  cloud->rgb.resize(cloud->xyz.size());
  for (size_t i = 0; i < cloud->rgb.size(); ++i) {
    const uint8_t* c = rgb->data() + 3 * i;
    cloud->rgb[i] = (uint32_t{c[0]} << 16) | (uint32_t{c[1]} << 8) | c[2];
  }
  return absl::OkStatus();
}

namespace {

absl::StatusOr<PointCloud> LoadCloudFile(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) {
    return absl::NotFoundError(absl::StrCat(path, ": no such file"));
  }
  if (!std::filesystem::is_regular_file(status)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not a regular file"));
  }
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  // PCL throws on some malformed input (std::out_of_range from a short
  // line, pcl::IOException, bad_alloc); none of that may escape.
  try {
    if (ext == ".pcd") return LoadPcd(path);
    if (ext == ".ply") return LoadPly(path);
    if (ext == ".png") return LoadDepthImage(path, options);
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": unreadable point cloud: ", e.what()));
  } catch (...) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": unreadable point cloud"));
  }
  return absl::InvalidArgumentError(absl::StrCat(path, ": unknown extension '", ext,
                                                 "' (expected .pcd, .ply or a 16-bit depth .png)"));
}

}  // namespace

PointCloud DepthToCloud(const std::vector<uint16_t>& depth, const CameraIntrinsics& camera,
                        double depth_scale_m) {
  PointCloud cloud;
  if (camera.width <= 0 || camera.height <= 0 ||
      depth.size() != static_cast<size_t>(camera.width) * camera.height) {
    return cloud;
  }
  cloud.width = camera.width;
  cloud.height = camera.height;
  cloud.xyz.resize(depth.size());
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const size_t i = static_cast<size_t>(v) * camera.width + u;
      if (depth[i] == 0 || depth[i] == 65535) {  // no return (65535 on some stereo cameras)
        cloud.xyz[i] = Eigen::Vector3f::Constant(kNaN);
        continue;
      }
      const double z = depth[i] * depth_scale_m;
      cloud.xyz[i] =
          Eigen::Vector3d((u - camera.cx) * z / camera.fx, (v - camera.cy) * z / camera.fy, z)
              .cast<float>();
    }
  }
  return cloud;
}

absl::Status SavePcd(const std::string& path, const PointCloud& cloud, bool binary) {
  if (absl::Status s = cloud.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not saved: ", s.message()));
  }
  const size_t n = cloud.size();
  // An empty cloud is written as 0 x 1, which PCL reads back as empty.
  const int width = n == 0 ? 0 : cloud.width;
  const int height = n == 0 ? 1 : cloud.height;
  std::unique_ptr<FILE, FileCloser> fp(std::fopen(path.c_str(), "wb"));
  if (fp == nullptr) {
    const int err = errno;
    return absl::ErrnoToStatus(err, absl::StrCat(path, ": cannot open for writing"));
  }
  const std::string header = absl::StrFormat(
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
      "TYPE F F F\nCOUNT 1 1 1\nWIDTH %d\nHEIGHT %d\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %d\n"
      "DATA %s\n",
      width, height, n, binary ? "binary" : "ascii");
  bool ok = std::fwrite(header.data(), 1, header.size(), fp.get()) == header.size();
  if (binary) {
    std::vector<float> data(3 * n);
    for (size_t i = 0; i < n; ++i) {
      for (int axis = 0; axis < 3; ++axis) data[3 * i + axis] = cloud.xyz[i][axis];
    }
    ok = ok && std::fwrite(data.data(), sizeof(float), data.size(), fp.get()) == data.size();
  } else {
    for (size_t i = 0; ok && i < n; ++i) {
      const Eigen::Vector3f& p = cloud.xyz[i];
      if (PointCloud::IsValid(p)) {
        ok = std::fprintf(fp.get(), "%.9g %.9g %.9g\n", p.x(), p.y(), p.z()) > 0;
      } else {
        ok = std::fputs("nan nan nan\n", fp.get()) >= 0;
      }
    }
  }
  ok = (std::fclose(fp.release()) == 0) && ok;
  if (!ok) {
    const int err = errno;
    const std::string message = absl::StrCat(path, ": write failed");
    return err != 0 ? absl::ErrnoToStatus(err, message) : absl::DataLossError(message);
  }
  return absl::OkStatus();
}

absl::Status SavePoints(const std::string& path, const std::vector<Eigen::Vector3f>& points) {
  PointCloud cloud;
  cloud.width = static_cast<int>(points.size());
  cloud.height = points.empty() ? 0 : 1;
  cloud.xyz = points;
  return SavePcd(path, cloud, /*binary=*/true);
}

absl::StatusOr<CameraIntrinsics> ParseIntrinsics(std::string_view std_text) {
  // Debian's abseil keeps its own string_view type.
  const absl::string_view text(std_text.data(), std_text.size());
  const std::vector<absl::string_view> parts = absl::StrSplit(text, ',');
  auto error = [&](absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat("intrinsics '", text, "': ", why,
                                                   " (expected fx,fy,cx,cy or "
                                                   "width,height,fx,fy,cx,cy)"));
  };
  if (parts.size() != 4 && parts.size() != 6) return error("wrong number of values");
  std::vector<double> values;
  for (absl::string_view part : parts) {
    double v = 0.0;
    if (!absl::SimpleAtod(absl::StripAsciiWhitespace(part), &v) || !std::isfinite(v)) {
      return error(absl::StrCat("'", part, "' is not a number"));
    }
    values.push_back(v);
  }
  CameraIntrinsics camera;
  size_t k = 0;
  if (values.size() == 6) {
    for (int i = 0; i < 2; ++i) {
      if (values[i] != std::floor(values[i]) || values[i] < 1 || values[i] > 1e6) {
        return error("width and height must be positive integers");
      }
    }
    camera.width = static_cast<int>(values[0]);
    camera.height = static_cast<int>(values[1]);
    k = 2;
  }
  camera.fx = values[k];
  camera.fy = values[k + 1];
  camera.cx = values[k + 2];
  camera.cy = values[k + 3];
  if (absl::Status s = camera.Validate(); !s.ok()) return error(s.message());
  return camera;
}

}  // namespace cornerpose
