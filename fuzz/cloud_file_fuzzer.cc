// PCD and PLY files through LoadPointCloud (common/io): the header checks,
// PCL's readers and the copy out of PCL's blob. Built twice, with
// CORNERPOSE_FUZZ_EXTENSION ".pcd" and ".ply". Any status is fine; a crash,
// a sanitizer report, a hang or a cloud that breaks its own invariants is a
// finding.
#include <cstddef>
#include <cstdint>

#include "common/io/cloud_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const cornerpose::fuzz::TempFile file("input" CORNERPOSE_FUZZ_EXTENSION);
  file.Write(data, size);
  const absl::StatusOr<cornerpose::PointCloud> cloud = cornerpose::LoadPointCloud(file.path());
  if (cloud.ok()) {
    cornerpose::fuzz::Require(cloud->Validate().ok(), "a loaded cloud validates");
    for (const Eigen::Vector3f& p : cloud->xyz) {
      // Non-finite coordinates become NaN in all three (cloud_io.h).
      cornerpose::fuzz::Require(p.allFinite() || p.array().isNaN().all(),
                                "a point is finite or all NaN");
    }
  } else {
    cornerpose::fuzz::Require(absl::IsInvalidArgument(cloud.status()),
                              "a bad file is INVALID_ARGUMENT");
  }
  return 0;
}
