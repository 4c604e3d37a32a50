// Sanity checks on PCD and PLY headers, run before handing a file to PCL.
// PCL trusts the header: a file that announces a billion points makes it
// allocate gigabytes (and get killed) before it notices the data is missing.
// These checks bound what the header may announce by what the file holds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace cornerpose {

// OK when the PCD header parses, has x, y and z fields of a supported type,
// and the body announced (ascii, binary or binary_compressed) fits in the
// file. INVALID_ARGUMENT naming the file and the problem otherwise.
absl::Status CheckPcdHeader(const std::string& path);

// The same for PLY: a known format, a vertex element with x, y and z, and
// element counts the body can hold.
absl::Status CheckPlyHeader(const std::string& path);

// The phases of CheckPcdHeader, for its tests. Errors carry no path.
namespace internal {

struct PcdField {
  std::string name;
  uint64_t size = 4;  // bytes of one value
  char type = 'F';    // F, I or U
  uint64_t count = 1;
};
enum class PcdData { kAscii, kBinary, kBinaryCompressed };
// What a header announces, up to its DATA line.
struct PcdHeader {
  std::vector<PcdField> fields;
  std::optional<uint64_t> width, height, points;
  PcdData data = PcdData::kAscii;
  size_t data_offset = 0;  // where the body starts
};
// Bytes of one point as stored (binary) and packed without "_" padding
// fields (binary_compressed), and values in it (ascii).
struct PcdLayout {
  uint64_t point_step = 0;
  uint64_t packed_step = 0;
  uint64_t values_per_point = 0;
};

// 1. The header lines, as PCL reads them: FIELDS, then SIZE, TYPE and COUNT
//    with one entry per field, counts that fit an int32, a DATA line.
absl::StatusOr<PcdHeader> ParsePcdHeader(absl::string_view head);
// 2. Supported field types (F 4/8, I/U 1/2/4 bytes) and x, y and z present.
absl::StatusOr<PcdLayout> PcdPointLayout(const std::vector<PcdField>& fields);
// 3. The number of points: WIDTH x HEIGHT must equal POINTS (a missing
//    WIDTH and HEIGHT, or HEIGHT, means one row, as in PCL).
absl::StatusOr<uint64_t> PcdPointCount(const PcdHeader& header);
// 4. The body the header announces fits in body_bytes; body_prefix holds
//    its first bytes (binary_compressed starts with the two block sizes).
absl::Status CheckPcdBodySize(PcdData data, const PcdLayout& layout, uint64_t points,
                              uint64_t body_bytes, absl::string_view body_prefix);

}  // namespace internal

}  // namespace cornerpose
