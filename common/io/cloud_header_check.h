// Sanity checks on PCD and PLY headers, run before handing a file to PCL.
// PCL trusts the header: a file that announces a billion points makes it
// allocate gigabytes (and get killed) before it notices the data is missing.
// These checks bound what the header may announce by what the file holds.
#pragma once

#include <string>

#include "absl/status/status.h"

namespace cornerpose {

// OK when the PCD header parses, has x, y and z fields of a supported type,
// and the body announced (ascii, binary or binary_compressed) fits in the
// file. INVALID_ARGUMENT naming the file and the problem otherwise.
absl::Status CheckPcdHeader(const std::string& path);

// The same for PLY: a known format, a vertex element with x, y and z, and
// element counts the body can hold.
absl::Status CheckPlyHeader(const std::string& path);

}  // namespace cornerpose
