#include "common/logging/log.h"

#include <atomic>
#include <chrono>
#include <ctime>
#include <iostream>
#include <mutex>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "nlohmann/json.hpp"

namespace cornerpose::logging {
namespace {

std::atomic<LogFormat> g_format{LogFormat::kText};
std::atomic<std::ostream*> g_stream{&std::cerr};
std::mutex g_write_mutex;

const char* LevelName(LogLevel level, bool upper) {
  switch (level) {
    case LogLevel::kDebug: return upper ? "DEBUG" : "debug";
    case LogLevel::kInfo: return upper ? "INFO" : "info";
    case LogLevel::kWarning: return upper ? "WARNING" : "warning";
    case LogLevel::kError: return upper ? "ERROR" : "error";
  }
  return "?";
}

// UTC, millisecond precision: RFC 3339 for JSON, the time of day for text.
std::string FormatTime(int64_t unix_nanos, bool full) {
  const std::time_t seconds = static_cast<std::time_t>(unix_nanos / 1000000000);
  const int millis = static_cast<int>((unix_nanos / 1000000) % 1000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  if (!full) return absl::StrFormat("%02d:%02d:%02d.%03d", tm.tm_hour, tm.tm_min, tm.tm_sec, millis);
  return absl::StrFormat("%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1,
                         tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, millis);
}

// A text value: bare unless it has spaces, quotes or '=' (then JSON-quoted).
std::string TextValue(const Field& f) {
  return std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>) {
          if (!v.empty() && v.find_first_of(" \"=\n\t") == std::string::npos) return v;
          return nlohmann::json(v).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        } else if constexpr (std::is_same_v<T, bool>) {
          return v ? "true" : "false";
        } else {
          return absl::StrCat(v);
        }
      },
      f.value);
}

}  // namespace

absl::StatusOr<LogFormat> ParseLogFormat(absl::string_view text) {
  if (text == "text") return LogFormat::kText;
  if (text == "json") return LogFormat::kJson;
  return absl::InvalidArgumentError(
      absl::StrCat("log format \"", text, "\" is neither \"text\" nor \"json\""));
}

void SetLogFormat(LogFormat format) { g_format.store(format); }
LogFormat GetLogFormat() { return g_format.load(); }
void SetLogStream(std::ostream* stream) { g_stream.store(stream ? stream : &std::cerr); }

std::string FormatLine(LogFormat format, int64_t unix_nanos, LogLevel level,
                       absl::string_view component, absl::string_view message,
                       std::initializer_list<Field> fields) {
  if (format == LogFormat::kText) {
    std::string line = absl::StrCat(FormatTime(unix_nanos, false), " ", LevelName(level, true),
                                    " ", component, ": ", message);
    for (const Field& f : fields) absl::StrAppend(&line, " ", f.key, "=", TextValue(f));
    return line;
  }
  // Fixed keys first, then the fields in the order given (ordered_json); a
  // field may not overwrite them.
  nlohmann::ordered_json line;
  line["time"] = FormatTime(unix_nanos, true);
  line["level"] = LevelName(level, false);
  line["component"] = std::string(component);
  line["message"] = std::string(message);
  for (const Field& f : fields) {
    const std::string key = line.contains(f.key) ? "field_" + f.key : f.key;
    std::visit([&](const auto& v) { line[key] = v; }, f.value);
  }
  // Invalid UTF-8 (a file name, say) is replaced, never thrown on.
  return line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

void Log(LogLevel level, absl::string_view component, absl::string_view message,
         std::initializer_list<Field> fields) {
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  const std::string line = FormatLine(g_format.load(), now, level, component, message, fields);
  std::lock_guard<std::mutex> lock(g_write_mutex);
  std::ostream& out = *g_stream.load();
  out << line << '\n';
  out.flush();
}

}  // namespace cornerpose::logging
