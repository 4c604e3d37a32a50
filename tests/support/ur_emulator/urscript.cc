#include "tests/support/ur_emulator/urscript.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"

namespace cornerpose::ur_emulator {
namespace {

// What a parameter accepts.
enum class ParamType {
  kNumber,
  kBool,
  kString,
  kAny,           // textmsg arguments
  kJointsOrPose,  // a list of 6 numbers or a pose
  kPose,          // a pose only
  kList3,         // a list of 3 numbers
};

struct Param {
  const char* name;
  ParamType type;
  std::optional<ScriptValue> default_value;  // none: required
};

struct Signature {
  const char* name;
  std::vector<Param> params;
  // Index range for parameter "n" (digital outputs); -1: no check.
  int max_index = -1;
};

ScriptValue Number(double v) {
  ScriptValue value;
  value.kind = ScriptValue::Kind::kNumber;
  value.number = v;
  return value;
}

ScriptValue String(std::string s) {
  ScriptValue value;
  value.kind = ScriptValue::Kind::kString;
  value.text = std::move(s);
  return value;
}

// Defaults as in the script manual (ur-interface.md section 3).
const std::vector<Signature>& Signatures() {
  static const auto* signatures = new std::vector<Signature>{
      {"movej",
       {{"q", ParamType::kJointsOrPose, std::nullopt},
        {"a", ParamType::kNumber, Number(1.4)},
        {"v", ParamType::kNumber, Number(1.05)},
        {"t", ParamType::kNumber, Number(0)},
        {"r", ParamType::kNumber, Number(0)}}},
      {"movel",
       {{"pose", ParamType::kJointsOrPose, std::nullopt},
        {"a", ParamType::kNumber, Number(1.2)},
        {"v", ParamType::kNumber, Number(0.25)},
        {"t", ParamType::kNumber, Number(0)},
        {"r", ParamType::kNumber, Number(0)}}},
      {"set_tool_digital_out",
       {{"n", ParamType::kNumber, std::nullopt}, {"b", ParamType::kBool, std::nullopt}},
       1},
      {"set_standard_digital_out",
       {{"n", ParamType::kNumber, std::nullopt}, {"b", ParamType::kBool, std::nullopt}},
       7},
      {"set_digital_out",
       {{"n", ParamType::kNumber, std::nullopt}, {"b", ParamType::kBool, std::nullopt}},
       7},
      {"set_configurable_digital_out",
       {{"n", ParamType::kNumber, std::nullopt}, {"b", ParamType::kBool, std::nullopt}},
       7},
      {"sleep", {{"t", ParamType::kNumber, std::nullopt}}},
      {"sync", {}},
      {"textmsg", {{"s1", ParamType::kAny, std::nullopt}, {"s2", ParamType::kAny, String("")}}},
      {"set_tcp", {{"pose", ParamType::kPose, std::nullopt}}},
      {"set_payload",
       {{"m", ParamType::kNumber, std::nullopt}, {"cog", ParamType::kList3, std::nullopt}}},
      {"stopl", {{"a", ParamType::kNumber, std::nullopt}}},
      {"stopj", {{"a", ParamType::kNumber, std::nullopt}}},
      {"protective_stop", {}},
      {"socket_open",
       {{"address", ParamType::kString, std::nullopt},
        {"port", ParamType::kNumber, std::nullopt},
        {"socket_name", ParamType::kString, String("socket_0")}}},
      {"socket_send_line",
       {{"str", ParamType::kAny, std::nullopt},
        {"socket_name", ParamType::kString, String("socket_0")}}},
      {"socket_send_string",
       {{"str", ParamType::kAny, std::nullopt},
        {"socket_name", ParamType::kString, String("socket_0")}}},
      {"socket_close", {{"socket_name", ParamType::kString, String("socket_0")}}},
  };
  return *signatures;
}

const Signature* FindSignature(absl::string_view name) {
  for (const Signature& s : Signatures()) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

bool IsIdentStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool IsIdentChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Thrown-free error carrier for the line parser.
struct LineError {
  int column = 0;  // 1-based
  std::string text;
};

// Parses one statement line (comment already stripped) into a call.
class LineParser {
 public:
  LineParser(absl::string_view line, int line_number, absl::string_view original)
      : s_(line), line_number_(line_number), original_(original) {}

  std::optional<LineError> Parse(ScriptCall& call) {
    SkipSpace();
    const size_t name_pos = pos_;
    if (!IsIdentStart(Peek())) return Syntax(pos_);
    std::string name = Identifier();
    SkipSpace();
    if (Peek() != '(') return Syntax(pos_);
    ++pos_;
    call.line = line_number_;
    call.column = static_cast<int>(name_pos) + 1;
    call.function = name;

    std::vector<ScriptValue> positional;
    std::vector<std::pair<std::string, ScriptValue>> keyword;
    SkipSpace();
    if (Peek() == ')') {
      ++pos_;
    } else {
      while (true) {
        SkipSpace();
        // keyword argument: ident '=' value (but not a pose literal `p[`)
        size_t save = pos_;
        std::string key;
        if (IsIdentStart(Peek())) {
          std::string ident = Identifier();
          SkipSpace();
          if (Peek() == '=') {
            ++pos_;
            key = ident;
          } else {
            pos_ = save;
          }
        }
        if (key.empty() && !keyword.empty()) return Syntax(pos_);
        ScriptValue value;
        if (auto error = Value(value)) return error;
        if (key.empty()) {
          positional.push_back(std::move(value));
        } else {
          keyword.emplace_back(key, std::move(value));
        }
        SkipSpace();
        if (Peek() == ',') {
          ++pos_;
          continue;
        }
        if (Peek() == ')') {
          ++pos_;
          break;
        }
        return Syntax(pos_);
      }
    }
    SkipSpace();
    if (pos_ != s_.size()) return Syntax(pos_);

    const Signature* signature = FindSignature(name);
    if (signature == nullptr) {
      return LineError{call.column, absl::StrCat("compile_error_name_not_found:", name, ":")};
    }
    return Bind(*signature, positional, keyword, call);
  }

 private:
  char Peek() const { return pos_ < s_.size() ? s_[pos_] : '\0'; }
  void SkipSpace() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t')) ++pos_;
  }
  std::string Identifier() {
    size_t start = pos_;
    while (pos_ < s_.size() && IsIdentChar(s_[pos_])) ++pos_;
    return std::string(s_.substr(start, pos_ - start));
  }
  LineError Syntax(size_t pos) const {
    return LineError{static_cast<int>(pos) + 1,
                     absl::StrCat("syntax_error_on_line:", line_number_, ":", original_, ":")};
  }

  std::optional<LineError> NumberLiteral(double& out) {
    SkipSpace();
    const size_t start = pos_;
    std::string text;
    if (Peek() == '-' || Peek() == '+') {
      text.push_back(Peek());
      ++pos_;
      SkipSpace();
    }
    const size_t digits = pos_;
    while (pos_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[pos_])) ||
                                s_[pos_] == '.' || s_[pos_] == 'e' || s_[pos_] == 'E' ||
                                ((s_[pos_] == '-' || s_[pos_] == '+') && pos_ > digits &&
                                 (s_[pos_ - 1] == 'e' || s_[pos_ - 1] == 'E')))) {
      text.push_back(s_[pos_]);
      ++pos_;
    }
    const bool starts_with_digit =
        pos_ > digits && (std::isdigit(static_cast<unsigned char>(s_[digits])) ||
                          (s_[digits] == '.' && digits + 1 < s_.size() &&
                           std::isdigit(static_cast<unsigned char>(s_[digits + 1]))));
    if (!starts_with_digit) {
      return Syntax(start);
    }
    char* end = nullptr;
    out = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !std::isfinite(out)) return Syntax(start);
    return std::nullopt;
  }

  // A list of numbers after '[' has been consumed, through ']'.
  std::optional<LineError> NumberList(std::vector<double>& out) {
    SkipSpace();
    if (Peek() == ']') {
      ++pos_;
      return std::nullopt;
    }
    while (true) {
      double v = 0;
      if (auto error = NumberLiteral(v)) return error;
      out.push_back(v);
      SkipSpace();
      if (Peek() == ',') {
        ++pos_;
        continue;
      }
      if (Peek() == ']') {
        ++pos_;
        return std::nullopt;
      }
      return Syntax(pos_);
    }
  }

  std::optional<LineError> Value(ScriptValue& value) {
    SkipSpace();
    const char c = Peek();
    if (c == '"' || c == '\'') {
      const size_t start = pos_;
      ++pos_;
      std::string text;
      while (pos_ < s_.size() && s_[pos_] != c) text.push_back(s_[pos_++]);
      if (pos_ >= s_.size()) return Syntax(start);
      ++pos_;
      value.kind = ScriptValue::Kind::kString;
      value.text = std::move(text);
      return std::nullopt;
    }
    if (c == '[') {
      ++pos_;
      value.kind = ScriptValue::Kind::kList;
      return NumberList(value.elements);
    }
    if (c == 'p' && pos_ + 1 < s_.size() && s_[pos_ + 1] == '[') {
      const size_t start = pos_;
      pos_ += 2;
      value.kind = ScriptValue::Kind::kPose;
      if (auto error = NumberList(value.elements)) return error;
      if (value.elements.size() != 6) return Syntax(start);
      return std::nullopt;
    }
    if (IsIdentStart(c)) {
      const size_t start = pos_;
      std::string ident = Identifier();
      if (ident == "True" || ident == "False") {
        value.kind = ScriptValue::Kind::kBool;
        value.boolean = ident == "True";
        return std::nullopt;
      }
      // A variable or a nested call: outside the subset.
      SkipSpace();
      if (Peek() == '(') {
        if (!FindSignature(ident)) {
          return LineError{static_cast<int>(start) + 1,
                           absl::StrCat("compile_error_name_not_found:", ident, ":")};
        }
        return Syntax(start);
      }
      return LineError{static_cast<int>(start) + 1,
                       absl::StrCat("compile_error_name_not_found:", ident, ":")};
    }
    value.kind = ScriptValue::Kind::kNumber;
    return NumberLiteral(value.number);
  }

  std::optional<LineError> Bind(const Signature& signature, std::vector<ScriptValue>& positional,
                                std::vector<std::pair<std::string, ScriptValue>>& keyword,
                                ScriptCall& call) {
    const std::string mismatch =
        absl::StrCat("compile_error_argument_mismatch:", signature.name, ":");
    if (positional.size() > signature.params.size()) return LineError{call.column, mismatch};
    for (size_t i = 0; i < positional.size(); ++i) {
      call.args[signature.params[i].name] = std::move(positional[i]);
    }
    for (auto& [key, value] : keyword) {
      bool known = false;
      for (const Param& p : signature.params) known |= key == p.name;
      if (!known || call.args.count(key)) return LineError{call.column, mismatch};
      call.args[key] = std::move(value);
    }
    for (const Param& p : signature.params) {
      auto it = call.args.find(p.name);
      if (it == call.args.end()) {
        if (!p.default_value) {
          // set_payload(m) without a centre of gravity is valid.
          if (std::string(signature.name) == "set_payload") continue;
          return LineError{call.column, mismatch};
        }
        call.args[p.name] = *p.default_value;
        continue;
      }
      const ScriptValue& v = it->second;
      bool ok = true;
      switch (p.type) {
        case ParamType::kNumber:
          ok = v.kind == ScriptValue::Kind::kNumber;
          break;
        case ParamType::kBool:
          ok = v.kind == ScriptValue::Kind::kBool;
          break;
        case ParamType::kString:
          ok = v.kind == ScriptValue::Kind::kString;
          break;
        case ParamType::kAny:
          break;
        case ParamType::kJointsOrPose:
          ok = v.kind == ScriptValue::Kind::kPose ||
               (v.kind == ScriptValue::Kind::kList && v.elements.size() == 6);
          break;
        case ParamType::kPose:
          ok = v.kind == ScriptValue::Kind::kPose;
          break;
        case ParamType::kList3:
          ok = v.kind == ScriptValue::Kind::kList && v.elements.size() == 3;
          break;
      }
      if (!ok) {
        return LineError{call.column, absl::StrCat("compile_error_type_mismatch:", signature.name,
                                                   ":", p.name, ":")};
      }
    }
    if (signature.max_index >= 0) {
      const double n = call.args.at("n").number;
      if (n != std::floor(n) || n < 0 || n > signature.max_index) {
        return LineError{call.column,
                         absl::StrCat("runtime_error_index_out_of_range:", signature.name, ":")};
      }
    }
    for (const char* name : {"a", "v", "t", "r", "m"}) {
      auto it = call.args.find(name);
      if (it != call.args.end() && it->second.kind == ScriptValue::Kind::kNumber &&
          it->second.number < 0) {
        return LineError{
            call.column,
            absl::StrCat("runtime_error_negative_argument:", signature.name, ":", name, ":")};
      }
    }
    return std::nullopt;
  }

  absl::string_view s_;
  size_t pos_ = 0;
  int line_number_;
  absl::string_view original_;
};

// The line without a trailing comment (a `#` outside a string) or `\r`.
absl::string_view StripComment(absl::string_view line) {
  char quote = 0;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#') {
      return line.substr(0, i);
    }
  }
  return line;
}

bool IsBlank(absl::string_view s) {
  for (char c : s) {
    if (c != ' ' && c != '\t' && c != '\r') return false;
  }
  return true;
}

ScriptError Error(int line, int column, std::string text) {
  return ScriptError{line, column, std::move(text)};
}

std::string FormatNumber(double v) {
  if (v == std::floor(v) && std::fabs(v) < 1e15) return absl::StrFormat("%.0f", v);
  return absl::StrFormat("%.10g", v);
}

}  // namespace

std::string ScriptValue::ToString() const {
  switch (kind) {
    case Kind::kNumber:
      return FormatNumber(number);
    case Kind::kBool:
      return boolean ? "True" : "False";
    case Kind::kString:
      return text;
    case Kind::kList:
    case Kind::kPose: {
      std::vector<std::string> parts;
      for (double e : elements) parts.push_back(FormatNumber(e));
      return absl::StrCat(kind == Kind::kPose ? "p[" : "[", absl::StrJoin(parts, ", "), "]");
    }
  }
  return "";
}

bool IsKnownFunction(absl::string_view name) { return FindSignature(name) != nullptr; }

ParseResult ParseScript(absl::string_view text) {
  ParseResult result;
  std::vector<absl::string_view> lines = absl::StrSplit(text, '\n');
  for (absl::string_view& line : lines) line = absl::StripSuffix(line, "\r");
  for (size_t i = 0; i < lines.size(); ++i) {
    for (char c : lines[i]) {
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t') {
        result.error = Error(static_cast<int>(i) + 1, 1,
                             absl::StrCat("syntax_error_on_line:", i + 1, ":", lines[i], ":"));
        return result;
      }
    }
  }

  // First non-blank, non-comment line decides: a program or bare statements.
  size_t first = 0;
  while (first < lines.size() && IsBlank(StripComment(lines[first]))) ++first;
  if (first == lines.size()) {
    result.error = Error(1, 1, "syntax_error_on_line:1:empty program:");
    return result;
  }

  auto parse_statement = [&](size_t i) -> std::optional<ScriptError> {
    absl::string_view code = StripComment(lines[i]);
    if (IsBlank(code)) return std::nullopt;
    ScriptCall call;
    LineParser parser(code, static_cast<int>(i) + 1, lines[i]);
    if (auto error = parser.Parse(call)) {
      return Error(static_cast<int>(i) + 1, error->column, error->text);
    }
    result.program.calls.push_back(std::move(call));
    return std::nullopt;
  };

  absl::string_view header = StripComment(lines[first]);
  const bool is_def = absl::StartsWith(header, "def ") || absl::StartsWith(header, "sec ");
  if (!is_def) {
    if (absl::StartsWith(absl::StripLeadingAsciiWhitespace(header), "def ") ||
        absl::StartsWith(absl::StripLeadingAsciiWhitespace(header), "sec ")) {
      const int column = static_cast<int>(header.find_first_not_of(" \t")) + 1;
      result.error =
          Error(static_cast<int>(first) + 1, column,
                absl::StrCat("syntax_error_on_line:", first + 1, ":", lines[first], ":"));
      return result;
    }
    result.program.name = "unnamed";
    for (size_t i = first; i < lines.size(); ++i) {
      if (auto error = parse_statement(i)) {
        result.error = error;
        result.program.calls.clear();
        return result;
      }
    }
    return result;
  }

  // def name():
  const int header_line = static_cast<int>(first) + 1;
  auto header_error = [&](size_t column) {
    result.error =
        Error(header_line, static_cast<int>(column) + 1,
              absl::StrCat("syntax_error_on_line:", header_line, ":", lines[first], ":"));
    return result;
  };
  size_t pos = 4;
  while (pos < header.size() && header[pos] == ' ') ++pos;
  const size_t name_start = pos;
  if (pos >= header.size() || !IsIdentStart(header[pos])) return header_error(pos);
  while (pos < header.size() && IsIdentChar(header[pos])) ++pos;
  std::string name(header.substr(name_start, pos - name_start));
  while (pos < header.size() && header[pos] == ' ') ++pos;
  if (header.substr(pos, 1) != "(") return header_error(pos);
  ++pos;
  while (pos < header.size() && header[pos] == ' ') ++pos;
  if (header.substr(pos, 1) != ")") return header_error(pos);
  ++pos;
  while (pos < header.size() && header[pos] == ' ') ++pos;
  if (header.substr(pos, 1) != ":") return header_error(pos);
  ++pos;
  if (!IsBlank(header.substr(pos))) return header_error(pos);
  result.program.name = name.substr(0, 31);

  // Body until `end` in column 1.
  size_t i = first + 1;
  bool ended = false;
  for (; i < lines.size(); ++i) {
    absl::string_view code = StripComment(lines[i]);
    if (IsBlank(code)) continue;
    if (code[0] != ' ' && code[0] != '\t') {
      if (absl::StripTrailingAsciiWhitespace(code) == "end") {
        ended = true;
        ++i;
        break;
      }
      result.error = Error(static_cast<int>(i) + 1, 1,
                           absl::StrCat("syntax_error_on_line:", i + 1, ":", lines[i], ":"));
      result.program.calls.clear();
      return result;
    }
    if (absl::StripLeadingAsciiWhitespace(code).substr(0, 3) == "end" &&
        IsBlank(absl::StripLeadingAsciiWhitespace(code).substr(3))) {
      // An indented `end` closes nothing in the subset (no blocks).
      const int column = static_cast<int>(code.find_first_not_of(" \t")) + 1;
      result.error = Error(static_cast<int>(i) + 1, column,
                           absl::StrCat("syntax_error_on_line:", i + 1, ":", lines[i], ":"));
      result.program.calls.clear();
      return result;
    }
    if (auto error = parse_statement(i)) {
      result.error = error;
      result.program.calls.clear();
      return result;
    }
  }
  if (!ended) {
    // Reported on the last line with content, as the file ends there.
    size_t last = lines.size();
    while (last > 1 && IsBlank(StripComment(lines[last - 1]))) --last;
    const int line = static_cast<int>(last);
    result.error = Error(line, 1, absl::StrCat("syntax_error_on_line:", line, ":end of file:"));
    result.program.calls.clear();
    return result;
  }
  for (; i < lines.size(); ++i) {
    if (!IsBlank(StripComment(lines[i]))) {
      result.error = Error(static_cast<int>(i) + 1, 1,
                           absl::StrCat("syntax_error_on_line:", i + 1, ":", lines[i], ":"));
      result.program.calls.clear();
      return result;
    }
  }
  return result;
}

}  // namespace cornerpose::ur_emulator
