// One log line per event, for both binaries: readable text (default) or,
// with --log_format json, one JSON object per line for log shippers
// (Fluent Bit, Vector, Loki's promtail):
//
//   {"time":"2024-12-01T22:41:07.512Z","level":"info","component":"server",
//    "message":"listening","address":"0.0.0.0:50051","port":50051}
//
// Text: 22:41:07.512 INFO server: listening address=0.0.0.0:50051 port=50051
#pragma once

#include <cstdint>
#include <initializer_list>
#include <ostream>
#include <string>
#include <variant>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace cornerpose::logging {

enum class LogFormat { kText, kJson };
enum class LogLevel { kDebug, kInfo, kWarning, kError };

// "text" or "json"; INVALID_ARGUMENT naming the value otherwise.
absl::StatusOr<LogFormat> ParseLogFormat(absl::string_view text);

// A named value attached to a line.
struct Field {
  std::string key;
  std::variant<std::string, double, int64_t, bool> value;

  Field(std::string k, absl::string_view v) : key(std::move(k)), value(std::string(v)) {}
  Field(std::string k, const std::string& v) : key(std::move(k)), value(v) {}
  Field(std::string k, const char* v) : key(std::move(k)), value(std::string(v)) {}
  Field(std::string k, double v) : key(std::move(k)), value(v) {}
  Field(std::string k, int v) : key(std::move(k)), value(int64_t{v}) {}
  Field(std::string k, int64_t v) : key(std::move(k)), value(v) {}
  Field(std::string k, uint64_t v) : key(std::move(k)), value(static_cast<int64_t>(v)) {}
  Field(std::string k, bool v) : key(std::move(k)), value(v) {}
};

// Process-wide settings; set once at start-up (main), before threads log.
void SetLogFormat(LogFormat format);
LogFormat GetLogFormat();
// Where lines go (default std::cerr); the stream must outlive the logging.
void SetLogStream(std::ostream* stream);

// Writes one line, whole (lines from different threads never interleave).
void Log(LogLevel level, absl::string_view component, absl::string_view message,
         std::initializer_list<Field> fields = {});

// The line Log() writes, without the newline (for tests and custom sinks);
// time in nanoseconds since the Unix epoch.
std::string FormatLine(LogFormat format, int64_t unix_nanos, LogLevel level,
                       absl::string_view component, absl::string_view message,
                       std::initializer_list<Field> fields);

}  // namespace cornerpose::logging
