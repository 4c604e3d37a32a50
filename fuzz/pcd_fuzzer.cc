// PCD bytes through ReadPcd (common/io/pcd_reader.h), the reader LoadPointCloud
// uses for .pcd: the header checks, then the ascii, binary or compressed body.
// Any status is fine; a crash, a sanitizer report, a hang or a cloud that
// breaks its own invariants is a finding.
#include <cstddef>
#include <cstdint>

#include "common/io/pcd_reader.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::StatusOr<cornerpose::PointCloud> cloud =
      cornerpose::ReadPcd(cornerpose::fuzz::AsText(data, size));
  if (cloud.ok()) {
    cornerpose::fuzz::Require(cloud->Validate().ok(), "a read cloud validates");
    for (const Eigen::Vector3f& p : cloud->xyz) {
      cornerpose::fuzz::Require(p.allFinite() || p.array().isNaN().all(),
                                "a point is finite or all NaN");
    }
  } else {
    cornerpose::fuzz::Require(absl::IsInvalidArgument(cloud.status()),
                              "a bad file is INVALID_ARGUMENT");
  }
  return 0;
}
