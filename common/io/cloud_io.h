// Loading and saving point clouds: PCD through our reader (pcd_reader.h), PLY
// through PCL, 16-bit depth PNGs through libpng. No PCL types cross this header.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/io/png_io.h"  // ReadDepthPng, WriteDepthPng
#include "common/perception/types.h"

namespace cornerpose {

struct LoadOptions {
  // Required for depth images; its width and height must match the image.
  std::optional<CameraIntrinsics> intrinsics;
  // Metres per depth unit of a depth image (millimetres by default).
  double depth_scale_m = 0.001;
  // A colour (or grey) PNG registered to an organized cloud, same width and
  // height: becomes PointCloud::rgb. Unset: a depth image NAME.png takes
  // NAME.color.png from beside it when there is one; a PCD keeps its own
  // rgb/rgba field.
  std::optional<std::string> color_path;
  // Whether a depth image NAME.png looks for NAME.color.png beside it when
  // color_path is unset (a mismatched one is then an error). The directory
  // source turns this off and attaches colour itself, leniently.
  bool color_from_beside = true;
};

// Loads a cloud, by extension (case-insensitive):
//   .pcd  ascii, binary or binary_compressed, any field order and extra fields;
//   .ply  ascii or binary, organized when it has a range grid;
//   .png  16-bit depth image, 0 = no return, converted with options.intrinsics.
// Colour comes from a PCD's rgb/rgba field (U or F, 0xAARRGGBB), from
// options.color_path, or from NAME.color.png beside a depth image NAME.png.
// Organized clouds keep their width x height and NaN points. A point with any
// non-finite coordinate becomes NaN in all three.
// NOT_FOUND for a missing file; INVALID_ARGUMENT for anything that is not a
// readable cloud (bad header, truncated data, no x/y/z, wrong PNG format,
// missing or mismatched intrinsics, unknown extension).
absl::StatusOr<PointCloud> LoadPointCloud(const std::string& path, const LoadOptions& options = {});

// Reads a colour PNG (8/16-bit, RGB, grey or palette) into cloud->rgb; the
// image must have the organized cloud's width and height (INVALID_ARGUMENT
// otherwise, NOT_FOUND when missing).
absl::Status AttachColor(const std::string& path, PointCloud* cloud);

// Back-projects a depth image (row-major, camera.width x camera.height) into
// an organized cloud: x = (u - cx) z / fx, y = (v - cy) z / fy, z = d *
// depth_scale_m; d = 0 and d = 65535 (no return on some stereo cameras) give NaN. Returns an empty
// cloud when depth.size() does not match the intrinsics.
PointCloud DepthToCloud(const std::vector<uint16_t>& depth, const CameraIntrinsics& camera,
                        double depth_scale_m);

// Writes a PCD v0.7 file with float x y z, binary or ascii; organized clouds
// keep width x height and NaNs.
absl::Status SavePcd(const std::string& path, const PointCloud& cloud, bool binary = true);

// Writes points as an unorganized binary PCD (width N, height 1), e.g. the
// edge points for the scorer. An empty list gives a valid empty file.
absl::Status SavePoints(const std::string& path, const std::vector<Eigen::Vector3f>& points);

// Parses "fx,fy,cx,cy" (image size left at the CameraIntrinsics default,
// 640 x 480) or "width,height,fx,fy,cx,cy". Spaces around values are allowed.
absl::StatusOr<CameraIntrinsics> ParseIntrinsics(std::string_view text);

}  // namespace cornerpose
