#include "common/io/cloud_header_check.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"

namespace cornerpose {
namespace {

// Headers are short; a "header" longer than this is not one.
constexpr size_t kMaxHeaderBytes = 1 << 20;
// PCL keeps sizes in 32-bit fields; refuse bodies it cannot index.
constexpr uint64_t kMaxBodyBytes = uint64_t{1} << 32;
// LZF never expands more than about 90x; a header that claims more is corrupt.
constexpr uint64_t kMaxLzfRatio = 128;

absl::Status Invalid(const std::string& path, absl::string_view what) {
  return absl::InvalidArgumentError(absl::StrCat(path, ": ", what));
}

// Reads up to kMaxHeaderBytes from the start of the file, and its size.
absl::Status ReadHead(const std::string& path, std::string* head, uint64_t* file_size) {
  std::error_code ec;
  *file_size = std::filesystem::file_size(path, ec);
  if (ec) return Invalid(path, absl::StrCat("cannot get the file size: ", ec.message()));
  std::ifstream in(path, std::ios::binary);
  if (!in) return Invalid(path, "cannot open the file for reading");
  head->resize(static_cast<size_t>(std::min<uint64_t>(*file_size, kMaxHeaderBytes)));
  in.read(head->data(), static_cast<std::streamsize>(head->size()));
  head->resize(static_cast<size_t>(in.gcount()));
  return absl::OkStatus();
}

// Splits a header line into whitespace-separated tokens, as PCL does.
std::vector<absl::string_view> Tokens(absl::string_view line) {
  return absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty());
}

// A non-negative decimal integer token, or nullopt.
std::optional<uint64_t> ParseCount(absl::string_view token) {
  uint64_t value = 0;
  if (token.empty() || token[0] == '-' || token[0] == '+' || !absl::SimpleAtoi(token, &value)) {
    return std::nullopt;
  }
  return value;
}

// Iterates over the lines of the header text; returns the offset just past
// the line it hands out, like tellg() after getline().
class LineReader {
 public:
  explicit LineReader(absl::string_view text) : text_(text) {}
  bool Next(absl::string_view* line) {
    if (pos_ >= text_.size()) return false;
    const size_t end = text_.find('\n', pos_);
    if (end == absl::string_view::npos) {
      // The last line must end inside what we read, or it may be cut.
      if (text_.size() >= kMaxHeaderBytes) return false;
      *line = text_.substr(pos_);
      pos_ = text_.size();
    } else {
      *line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
    }
    return true;
  }
  size_t offset() const { return pos_; }

 private:
  absl::string_view text_;
  size_t pos_ = 0;
};

}  // namespace

namespace internal {
namespace {

bool Is(absl::string_view key, absl::string_view keyword) { return absl::StartsWith(key, keyword); }

// FIELDS / COLUMNS: a new field list; SIZE, TYPE and COUNT must follow again.
void OnFieldsLine(const std::vector<absl::string_view>& st, PcdHeader* header, bool* have_size,
                  bool* have_type) {
  header->fields.assign(st.size() - 1, PcdField{});
  for (size_t i = 1; i < st.size(); ++i) header->fields[i - 1].name = std::string(st[i]);
  *have_size = *have_type = false;
}

// SIZE, TYPE or COUNT: one entry per field, in that order.
absl::Status OnPerFieldLine(const std::vector<absl::string_view>& st, PcdHeader* header,
                            bool* have_size, bool* have_type) {
  const absl::string_view key = st[0];
  const size_t n = st.size() - 1;
  std::vector<PcdField>& fields = header->fields;
  if (n != fields.size() || fields.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("PCD header line '", key, "' has ", n,
                                                   " entries for ", fields.size(), " FIELDS"));
  }
  for (size_t i = 0; i < n; ++i) {
    if (Is(key, "TYPE")) {
      if (st[i + 1].size() != 1) {
        return absl::InvalidArgumentError("PCD TYPE entries must be F, I or U");
      }
      fields[i].type = st[i + 1][0];
      continue;
    }
    const std::optional<uint64_t> v = ParseCount(st[i + 1]);
    if (!v || *v == 0 || *v > 1000000) {
      return absl::InvalidArgumentError(
          absl::StrCat("PCD ", key, " entry '", st[i + 1], "' is not valid"));
    }
    (Is(key, "SIZE") ? fields[i].size : fields[i].count) = *v;
  }
  if (Is(key, "SIZE")) *have_size = true;
  if (Is(key, "TYPE")) {
    if (!*have_size) return absl::InvalidArgumentError("PCD TYPE comes before SIZE");
    *have_type = true;
  }
  if (Is(key, "COUNT") && (!*have_size || !*have_type)) {
    return absl::InvalidArgumentError("PCD COUNT comes before SIZE or TYPE");
  }
  return absl::OkStatus();
}

// WIDTH, HEIGHT or POINTS: one count that fits PCL's int32.
absl::Status OnCountLine(const std::vector<absl::string_view>& st, absl::string_view line,
                         PcdHeader* header) {
  const std::optional<uint64_t> v = st.size() >= 2 ? ParseCount(st[1]) : std::nullopt;
  if (!v || *v > std::numeric_limits<int32_t>::max()) {
    return absl::InvalidArgumentError(
        absl::StrCat("PCD header line '", line, "' has no valid count"));
  }
  (Is(st[0], "WIDTH") ? header->width : Is(st[0], "HEIGHT") ? header->height : header->points) =
      *v;
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<PcdHeader> ParsePcdHeader(absl::string_view head) {
  PcdHeader header;
  bool have_size = false, have_type = false, have_data = false;
  LineReader lines(head);
  absl::string_view line;
  while (!have_data && lines.Next(&line)) {
    const std::vector<absl::string_view> st = Tokens(line);
    if (st.empty()) continue;
    const absl::string_view key = st[0];
    if (Is(key, "#") || Is(key, "VERSION") || Is(key, "VIEWPOINT")) continue;
    absl::Status status;
    if (Is(key, "FIELDS") || Is(key, "COLUMNS")) {
      OnFieldsLine(st, &header, &have_size, &have_type);
    } else if (Is(key, "SIZE") || Is(key, "TYPE") || Is(key, "COUNT")) {
      status = OnPerFieldLine(st, &header, &have_size, &have_type);
    } else if (Is(key, "WIDTH") || Is(key, "HEIGHT") || Is(key, "POINTS")) {
      status = OnCountLine(st, line, &header);
    } else if (Is(key, "DATA")) {
      if (st.size() < 2) return absl::InvalidArgumentError("PCD DATA line names no format");
      header.data = Is(st[1], "binary_compressed") ? PcdData::kBinaryCompressed
                    : Is(st[1], "binary")          ? PcdData::kBinary
                                                   : PcdData::kAscii;
      header.data_offset = lines.offset();
      have_data = true;
    } else {
      return absl::InvalidArgumentError(absl::StrCat(
          "not a PCD file: unexpected header line '", line.substr(0, 40), "'"));
    }
    if (!status.ok()) return status;
  }
  if (!have_data) return absl::InvalidArgumentError("not a PCD file: no DATA line in its header");
  // Without them PCL lays the fields out at offset 0 with no size (found by
  // pcd_fuzzer: its ascii reader then wrote outside the cloud).
  if (!have_size || !have_type) {
    return absl::InvalidArgumentError("PCD header has no SIZE and TYPE lines after its FIELDS");
  }
  // PCL reads on past DATA while the lines look like header lines, and obeys
  // them (found by pcd_fuzzer: a FIELDS line after DATA crashed its reader).
  while (lines.Next(&line)) {
    const std::vector<absl::string_view> st = Tokens(line);
    if (st.empty() || Is(st[0], "#") || Is(st[0], "VERSION") || Is(st[0], "VIEWPOINT")) continue;
    for (const char* keyword :
         {"FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "POINTS", "DATA"}) {
      if (Is(st[0], keyword)) {
        return absl::InvalidArgumentError(
            absl::StrCat("PCD header line '", line.substr(0, 40), "' after DATA"));
      }
    }
    break;
  }
  return header;
}

absl::StatusOr<PcdLayout> PcdPointLayout(const std::vector<PcdField>& fields) {
  bool has_x = false, has_y = false, has_z = false;
  PcdLayout layout;
  for (const PcdField& f : fields) {
    const bool ok_type =
        (f.type == 'F' && (f.size == 4 || f.size == 8)) ||
        ((f.type == 'I' || f.type == 'U') && (f.size == 1 || f.size == 2 || f.size == 4));
    if (!ok_type) {
      return absl::InvalidArgumentError(absl::StrCat("PCD field '", f.name,
                                                     "' has unsupported type ",
                                                     std::string(1, f.type), " of size ", f.size));
    }
    layout.point_step += f.size * f.count;
    if (f.name != "_") layout.packed_step += f.size * f.count;
    layout.values_per_point += f.count;
    has_x |= f.name == "x";
    has_y |= f.name == "y";
    has_z |= f.name == "z";
  }
  if (!has_x || !has_y || !has_z) {
    return absl::InvalidArgumentError("PCD file has no x, y and z fields");
  }
  return layout;
}

absl::StatusOr<uint64_t> PcdPointCount(const PcdHeader& header) {
  if (!header.points) return absl::InvalidArgumentError("PCD header has no POINTS line");
  const uint64_t points = *header.points;
  // As PCL reads it: no WIDTH and HEIGHT, or no HEIGHT, is one row.
  uint64_t w = header.width.value_or(0), h = header.height.value_or(0);
  if (w == 0 && h == 0) w = points, h = 1;
  if (h == 0) h = 1, w = w == 0 ? points : w;
  if (w * h != points) {
    return absl::InvalidArgumentError(
        absl::StrCat("PCD WIDTH x HEIGHT = ", w, " x ", h, " but POINTS is ", points));
  }
  return points;
}

absl::Status CheckPcdBodySize(PcdData data, const PcdLayout& layout, uint64_t points,
                              uint64_t body_bytes, absl::string_view body_prefix) {
  const uint64_t need = points * layout.point_step;
  if (need > kMaxBodyBytes) {
    return absl::InvalidArgumentError(
        absl::StrCat("PCD header announces ", need, " bytes of points, too many"));
  }
  switch (data) {
    case PcdData::kAscii:
      // Each value takes at least one character and one separator.
      if (points * layout.values_per_point * 2 > body_bytes + 1) {
        return absl::InvalidArgumentError(absl::StrCat("PCD ascii body of ", body_bytes,
                                                       " bytes is too short for ", points,
                                                       " points (truncated file?)"));
      }
      return absl::OkStatus();
    case PcdData::kBinary:
      if (need > body_bytes) {
        return absl::InvalidArgumentError(absl::StrCat("PCD binary body holds ", body_bytes,
                                                       " bytes, ", need,
                                                       " expected (truncated file?)"));
      }
      return absl::OkStatus();
    case PcdData::kBinaryCompressed:
      break;
  }
  if (points == 0) return absl::OkStatus();
  if (body_bytes < 8 || body_prefix.size() < 8) {
    return absl::InvalidArgumentError("PCD binary_compressed body is truncated");
  }
  uint32_t compressed = 0, uncompressed = 0;
  std::memcpy(&compressed, body_prefix.data(), 4);
  std::memcpy(&uncompressed, body_prefix.data() + 4, 4);
  if (uint64_t{compressed} + 8 > body_bytes) {
    return absl::InvalidArgumentError(absl::StrCat("PCD compressed block of ", compressed,
                                                   " bytes but only ", body_bytes - 8,
                                                   " in the file (truncated file?)"));
  }
  if (uncompressed != points * layout.packed_step ||
      uncompressed > uint64_t{compressed} * kMaxLzfRatio + 1024) {
    return absl::InvalidArgumentError(absl::StrCat("PCD compressed block expands to ",
                                                   uncompressed, " bytes, which does not match ",
                                                   points, " points"));
  }
  return absl::OkStatus();
}

}  // namespace internal

absl::Status CheckPcdHeader(const std::string& path) {
  std::string head;
  uint64_t file_size = 0;
  if (absl::Status s = ReadHead(path, &head, &file_size); !s.ok()) return s;
  if (file_size == 0) return Invalid(path, "empty file, not a PCD point cloud");
  const auto with_path = [&](const absl::Status& s) { return Invalid(path, s.message()); };

  const absl::StatusOr<internal::PcdHeader> header = internal::ParsePcdHeader(head);
  if (!header.ok()) return with_path(header.status());
  const absl::StatusOr<internal::PcdLayout> layout = internal::PcdPointLayout(header->fields);
  if (!layout.ok()) return with_path(layout.status());
  const absl::StatusOr<uint64_t> points = internal::PcdPointCount(*header);
  if (!points.ok()) return with_path(points.status());

  // The compressed block's two sizes open the body; read them from the file
  // when the header filled all that ReadHead() took.
  std::string body_prefix = head.substr(std::min(head.size(), header->data_offset), 8);
  if (body_prefix.size() < 8 && header->data_offset + 8 <= file_size) {
    std::ifstream in(path, std::ios::binary);
    body_prefix.resize(8);
    in.seekg(static_cast<std::streamoff>(header->data_offset));
    if (!in.read(body_prefix.data(), 8)) return Invalid(path, "cannot read the PCD body");
  }
  if (absl::Status s = internal::CheckPcdBodySize(header->data, *layout, *points,
                                                  file_size - header->data_offset, body_prefix);
      !s.ok()) {
    return with_path(s);
  }
  return absl::OkStatus();
}

namespace {

// Bytes of one PLY scalar type, 0 when unknown.
uint64_t PlyTypeSize(absl::string_view type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32") return 4;
  if (type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  uint64_t min_bytes = 0;  // the least one instance can take in the body
  int properties = 0;
  bool has_x = false, has_y = false, has_z = false;
  // PCL's vertex handling sizes the points up front and asserts (aborts) or
  // writes fields out of place when lists vary in length or uchar colours do
  // not pair up into its packed "rgb".
  int lists = 0;
  int reds = 0, blues = 0;
  bool alpha_before_red = false;
};

}  // namespace

absl::Status CheckPlyHeader(const std::string& path) {
  std::string head;
  uint64_t file_size = 0;
  if (absl::Status s = ReadHead(path, &head, &file_size); !s.ok()) return s;

  LineReader lines(head);
  absl::string_view line;
  if (!lines.Next(&line) || absl::StripAsciiWhitespace(line) != "ply") {
    return Invalid(path, "not a PLY file: it does not start with 'ply'");
  }
  std::string format;
  std::vector<PlyElement> elements;
  // PCL takes the organized size from obj_info lines (atoi, 32-bit).
  uint32_t cols = 0, rows = 0;
  uint64_t cloud_w = 0, cloud_h = 0;
  bool ended = false;
  while (lines.Next(&line)) {
    const std::vector<absl::string_view> st = Tokens(line);
    if (st.empty()) continue;
    if (st[0] == "end_header") {
      ended = true;
      break;
    }
    if (st[0] == "comment") continue;
    if (st[0] == "format") {
      if (st.size() < 3) return Invalid(path, "PLY format line is incomplete");
      format = std::string(st[1]);
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        return Invalid(path, absl::StrCat("PLY format '", format, "' is unknown"));
      }
    } else if (st[0] == "obj_info") {
      if (st.size() >= 3 && (st[1] == "num_cols" || st[1] == "num_rows")) {
        const uint32_t v = static_cast<uint32_t>(std::atoi(std::string(st[2]).c_str()));
        (st[1] == "num_cols" ? cols : rows) = v;
        (st[1] == "num_cols" ? cloud_w : cloud_h) = v;
      }
    } else if (st[0] == "element") {
      const std::optional<uint64_t> count = st.size() == 3 ? ParseCount(st[2]) : std::nullopt;
      if (!count) return Invalid(path, absl::StrCat("PLY element line '", line, "' is invalid"));
      elements.push_back(PlyElement{std::string(st[1]), *count});
      if (st[1] == "vertex" && (cloud_w == 0 || cloud_h == 0)) cloud_w = *count, cloud_h = 1;
    } else if (st[0] == "property") {
      if (elements.empty()) return Invalid(path, "PLY property comes before any element");
      PlyElement& e = elements.back();
      const bool ascii = format == "ascii";
      if (st.size() == 5 && st[1] == "list") {
        const uint64_t size_bytes = PlyTypeSize(st[2]);
        if (size_bytes == 0 || PlyTypeSize(st[3]) == 0) {
          return Invalid(path, absl::StrCat("PLY property line '", line, "' has unknown types"));
        }
        e.min_bytes += ascii ? 2 : size_bytes;
        ++e.lists;
      } else if (st.size() == 3) {
        const uint64_t bytes = PlyTypeSize(st[1]);
        if (bytes == 0) {
          return Invalid(path, absl::StrCat("PLY property type '", st[1], "' is unknown"));
        }
        e.min_bytes += ascii ? 2 : bytes;
        e.has_x |= st[2] == "x";
        e.has_y |= st[2] == "y";
        e.has_z |= st[2] == "z";
        if (st[1] == "uchar" || st[1] == "uint8") {
          e.reds += st[2] == "red" || st[2] == "diffuse_red";
          e.blues += st[2] == "blue" || st[2] == "diffuse_blue";
          e.alpha_before_red |= st[2] == "alpha" && e.reds == 0;
        }
      } else {
        return Invalid(path, absl::StrCat("PLY property line '", line, "' is invalid"));
      }
      ++e.properties;
    } else {
      return Invalid(
          path, absl::StrCat("not a PLY file: unexpected header line '", line.substr(0, 40), "'"));
    }
  }
  if (!ended) return Invalid(path, "not a PLY file: no end_header line");
  if (format.empty()) return Invalid(path, "PLY header has no format line");

  const uint64_t body = file_size - lines.offset();
  uint64_t need = 0, vertices = 0, grid = 0;
  bool has_xyz = false;
  int vertex_elements = 0;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") {
      if (++vertex_elements > 1) return Invalid(path, "PLY file has two vertex elements");
      if (e.lists > 0) return Invalid(path, "PLY vertex list properties are not supported");
      if (e.reds != e.blues || e.alpha_before_red) {
        return Invalid(path, "PLY vertex colours are not red, green, blue (and alpha) uchar");
      }
    }
    if (e.count > 0 && e.properties == 0) {
      return Invalid(path, absl::StrCat("PLY element '", e.name, "' has no properties"));
    }
    if (e.count > kMaxBodyBytes) {
      return Invalid(path, absl::StrCat("PLY element '", e.name, "' count is too large"));
    }
    need += e.count * e.min_bytes;
    if (e.name == "vertex") {
      vertices = e.count;
      has_xyz = e.has_x && e.has_y && e.has_z;
    }
    if (e.name == "range_grid") grid = e.count;
  }
  if (!has_xyz) return Invalid(path, "PLY file has no vertex element with x, y and z");
  // The last ascii value may lack its trailing newline.
  if (need > body + (format == "ascii" ? 1 : 0)) {
    return Invalid(path, absl::StrCat("PLY body of ", body, " bytes is too short for the ", need,
                                      " its header announces (truncated file?)"));
  }
  // PCL allocates width x height points up front and fills them with the
  // vertices.
  if (cloud_w * cloud_h > std::max<uint64_t>({vertices, grid, 1}) || cloud_w * cloud_h < vertices) {
    return Invalid(path, absl::StrCat("PLY obj_info size ", cols, " x ", rows,
                                      " does not match its ", vertices, " vertices"));
  }
  return absl::OkStatus();
}

}  // namespace cornerpose
