#include "common/io/pcd_reader.h"

#include <pcl/io/lzf.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/io/cloud_header_check.h"

namespace cornerpose {
namespace {

using internal::PcdData;
using internal::PcdField;
using internal::PcdHeader;
using internal::PcdLayout;

// As in CheckPcdHeader: a header longer than this is not one.
constexpr size_t kMaxHeaderBytes = 1 << 20;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

template <typename... Args>
absl::Status Invalid(const Args&... args) {
  return absl::InvalidArgumentError(absl::StrCat(args...));
}

std::string TypeName(const PcdField& f) { return absl::StrCat(std::string(1, f.type), f.size); }

// A value quoted in an error, cut short.
std::string Quote(absl::string_view token) {
  return absl::StrCat("'", token.substr(0, 24), token.size() > 24 ? "...'" : "'");
}

// One field the cloud keeps, and where its first value sits in each layout.
struct Kept {
  const PcdField* field = nullptr;
  uint64_t offset = 0;  // bytes into a stored point (binary)
  uint64_t value = 0;   // values before it on an ascii line
  uint64_t block = 0;   // bytes before its block (binary_compressed)
};
struct Plan {
  Kept xyz[3];
  std::optional<Kept> colour;
};

Plan PlanFields(const std::vector<PcdField>& fields, uint64_t points) {
  Plan plan;
  bool have[3] = {false, false, false};
  uint64_t offset = 0, value = 0, block = 0;
  for (const PcdField& f : fields) {
    const Kept here{&f, offset, value, block};
    for (int axis = 0; axis < 3; ++axis) {
      if (!have[axis] && f.name == std::string(1, static_cast<char>('x' + axis))) {
        plan.xyz[axis] = here;
        have[axis] = true;
      }
    }
    if (!plan.colour && (f.name == "rgb" || f.name == "rgba") && f.size == 4) plan.colour = here;
    offset += f.size * f.count;
    value += f.count;
    if (f.name != "_") block += f.size * f.count * points;
  }
  return plan;  // PcdPointLayout made sure x, y and z are there
}

template <typename T>
T LoadAs(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// A stored value of a supported type (PcdPointLayout checked it) as double.
double BinaryValue(const char* p, const PcdField& f) {
  switch (f.type) {
    case 'F':
      return f.size == 4 ? LoadAs<float>(p) : LoadAs<double>(p);
    case 'I':
      return f.size == 1 ? LoadAs<int8_t>(p) : f.size == 2 ? LoadAs<int16_t>(p) : LoadAs<int32_t>(p);
    default:
      return f.size == 1   ? LoadAs<uint8_t>(p)
             : f.size == 2 ? LoadAs<uint16_t>(p)
                           : LoadAs<uint32_t>(p);
  }
}

// Rounds to float without the undefined behaviour of an out-of-range cast.
float ToFloat(double d) {
  if (std::isnan(d)) return kNaN;
  if (d > std::numeric_limits<float>::max()) return std::numeric_limits<float>::infinity();
  if (d < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(d);
}

// A whole token as a floating-point number (nan and inf allowed, as PCL
// writes them); out of range is +-inf or 0, as strtod gives it.
template <typename T>
bool ParseReal(absl::string_view token, T* out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const std::from_chars_result r = std::from_chars(token.data(), end, *out);
  if (r.ptr != end || token.empty()) return false;
  if (r.ec == std::errc::result_out_of_range) {
    const double d = std::strtod(std::string(token).c_str(), nullptr);
    *out = static_cast<T>(std::is_same_v<T, float> ? ToFloat(d) : d);
    return true;
  }
  return r.ec == std::errc();
}

template <typename T>
bool ParseInt(absl::string_view token, T* out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const std::from_chars_result r = std::from_chars(token.data(), end, *out);
  return !token.empty() && r.ptr == end && r.ec == std::errc();
}

// One ascii value of field f, as double.
bool AsciiValue(absl::string_view token, const PcdField& f, double* out) {
  if (f.type == 'F') {
    if (f.size == 8) return ParseReal(token, out);
    float v = 0;
    if (!ParseReal(token, &v)) return false;
    *out = v;
    return true;
  }
  if (f.type == 'I') {
    int64_t v = 0;
    const int64_t lim = int64_t{1} << (8 * f.size - 1);
    if (!ParseInt(token, &v) || v < -lim || v >= lim) return false;
    *out = static_cast<double>(v);
    return true;
  }
  uint64_t v = 0;
  if (!ParseInt(token, &v) || v >= (uint64_t{1} << (8 * f.size))) return false;
  *out = static_cast<double>(v);
  return true;
}

// The 32 bits of an ascii colour value: an integer for U and I, a float
// whose bits are the colour for F (as PCL reads and writes it: the token
// 4294967295 in an F field is the float 2^32, not white).
bool AsciiColour(absl::string_view token, const PcdField& f, uint32_t* out) {
  if (f.type == 'U') return ParseInt(token, out);
  if (f.type == 'I') {
    int32_t i = 0;
    if (!ParseInt(token, &i)) return false;
    *out = static_cast<uint32_t>(i);
    return true;
  }
  float v = 0;
  if (!ParseReal(token, &v)) return false;
  std::memcpy(out, &v, 4);
  return true;
}

absl::Status BadValue(uint64_t point, const PcdField& f, absl::string_view token) {
  return Invalid("PCD ascii point ", point, ": field '", f.name, "' value ", Quote(token),
                 " is not a ", TypeName(f), " number");
}

void SetPoint(PointCloud* cloud, size_t i, const double v[3]) {
  const Eigen::Vector3f p(ToFloat(v[0]), ToFloat(v[1]), ToFloat(v[2]));
  cloud->xyz[i] = p.allFinite() ? p : Eigen::Vector3f::Constant(kNaN);
}

absl::Status ReadAscii(absl::string_view body, const PcdLayout& layout, const Plan& plan,
                       PointCloud* cloud) {
  const size_t n = cloud->xyz.size();
  size_t pos = 0;
  std::vector<absl::string_view> tokens;
  for (size_t i = 0; i < n;) {
    if (pos >= body.size()) {
      return Invalid("PCD ascii body ends after ", i, " of ", n, " points (truncated file?)");
    }
    size_t end = body.find('\n', pos);
    if (end == absl::string_view::npos) end = body.size();
    const absl::string_view line = body.substr(pos, end - pos);
    pos = end + 1;
    tokens = absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty());
    if (tokens.empty()) continue;
    if (tokens.size() != layout.values_per_point) {
      return Invalid("PCD ascii point ", i, " has ", tokens.size(), " values, expected ",
                     layout.values_per_point, " (the header's FIELDS times COUNT)");
    }
    double v[3];
    for (int axis = 0; axis < 3; ++axis) {
      const Kept& k = plan.xyz[axis];
      if (!AsciiValue(tokens[k.value], *k.field, &v[axis])) {
        return BadValue(i, *k.field, tokens[k.value]);
      }
    }
    SetPoint(cloud, i, v);
    if (plan.colour) {
      uint32_t packed = 0;
      if (!AsciiColour(tokens[plan.colour->value], *plan.colour->field, &packed)) {
        return BadValue(i, *plan.colour->field, tokens[plan.colour->value]);
      }
      cloud->rgb[i] = packed & 0x00FFFFFFu;
    }
    ++i;
  }
  if (pos < body.size() && !absl::StripAsciiWhitespace(body.substr(pos)).empty()) {
    return Invalid("PCD ascii body holds more than the ", n, " points its header announces");
  }
  return absl::OkStatus();
}

// Points from a body of fixed-size records; value(i, kept) points at the
// first byte of point i's value of that field. Sizes were checked before.
template <typename Locate>
void ReadFixed(const Plan& plan, const Locate& value, PointCloud* cloud) {
  for (size_t i = 0; i < cloud->xyz.size(); ++i) {
    double v[3];
    for (int axis = 0; axis < 3; ++axis) {
      v[axis] = BinaryValue(value(i, plan.xyz[axis]), *plan.xyz[axis].field);
    }
    SetPoint(cloud, i, v);
    if (plan.colour) cloud->rgb[i] = LoadAs<uint32_t>(value(i, *plan.colour)) & 0x00FFFFFFu;
  }
}

}  // namespace

absl::StatusOr<PointCloud> ReadPcd(absl::string_view bytes) {
  if (bytes.empty()) return Invalid("empty file, not a PCD point cloud");
  // The header phases of CheckPcdHeader (cloud_header_check.h).
  const absl::StatusOr<PcdHeader> header =
      internal::ParsePcdHeader(bytes.substr(0, kMaxHeaderBytes));
  if (!header.ok()) return header.status();
  const absl::StatusOr<PcdLayout> layout = internal::PcdPointLayout(header->fields);
  if (!layout.ok()) return layout.status();
  const absl::StatusOr<uint64_t> points = internal::PcdPointCount(*header);
  if (!points.ok()) return points.status();
  const absl::string_view body = bytes.substr(header->data_offset);
  if (absl::Status s =
          internal::CheckPcdBodySize(header->data, *layout, *points, body.size(), body.substr(0, 8));
      !s.ok()) {
    return s;
  }

  PointCloud cloud;
  if (*points == 0) return cloud;
  // The organized size as PcdPointCount reads it (no HEIGHT: one row).
  const uint64_t height = header->height.value_or(0) == 0 ? 1 : *header->height;
  cloud.width = static_cast<int>(*points / height);
  cloud.height = static_cast<int>(height);
  cloud.xyz.resize(*points);
  const Plan plan = PlanFields(header->fields, *points);
  if (plan.colour) cloud.rgb.resize(*points);

  switch (header->data) {
    case PcdData::kAscii:
      if (absl::Status s = ReadAscii(body, *layout, plan, &cloud); !s.ok()) return s;
      return cloud;
    case PcdData::kBinary:
      ReadFixed(
          plan,
          [&](size_t i, const Kept& k) { return body.data() + i * layout->point_step + k.offset; },
          &cloud);
      return cloud;
    case PcdData::kBinaryCompressed:
      break;
  }
  // Two sizes, then one LZF block holding each field's values for all
  // points, field after field ("_" padding left out). CheckPcdBodySize made
  // sure the block is in the body and expands to exactly the packed points.
  uint32_t compressed = 0, expanded = 0;
  std::memcpy(&compressed, body.data(), 4);
  std::memcpy(&expanded, body.data() + 4, 4);
  if (compressed == 0) return Invalid("PCD binary_compressed block is empty");
  std::string fields(expanded, '\0');
  const unsigned int got = pcl::lzfDecompress(body.data() + 8, compressed, fields.data(), expanded);
  if (got != expanded) {
    return Invalid("PCD binary_compressed block of ", compressed, " bytes decompresses to ", got,
                   " bytes, expected ", expanded, " (corrupt data)");
  }
  ReadFixed(
      plan,
      [&](size_t i, const Kept& k) {
        return fields.data() + k.block + i * k.field->size * k.field->count;
      },
      &cloud);
  return cloud;
}

}  // namespace cornerpose
