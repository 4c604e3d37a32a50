// Reads a PCD file's bytes into a PointCloud without PCL's reader, which
// trusts the file (the PCD fuzzer made it fault on a mislabelled binary
// body). The header goes through the checks of cloud_header_check.h; the
// body is read here with every size checked against the bytes there are.
#pragma once

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/perception/types.h"

namespace cornerpose {

// A PCD file held in memory: DATA ascii, binary or binary_compressed (PCL's
// LZF block, fields one after another), fields in any order with any COUNT.
// Keeps x, y, z (F 4/8, I or U; the first element of each) and colour from
// the first 4-byte rgb or rgba field (U, I, or F holding the same bits; packed
// 0xAARRGGBB, alpha dropped); other fields and "_" padding are skipped.
// Organized clouds keep width x height and NaN points; a point with any
// non-finite coordinate is NaN in all three. INVALID_ARGUMENT naming what is
// wrong (line, point, field, value, what was expected) for anything else.
absl::StatusOr<PointCloud> ReadPcd(absl::string_view bytes);

}  // namespace cornerpose
