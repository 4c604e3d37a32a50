// The subset of URScript the UR controller emulator executes: a program
// `def name():` ... `end` (or bare statements) made of calls to a fixed set
// of built-ins with literal arguments. Anything outside the subset is an
// error with the 1-based line and column the real controller would report,
// so a test sees the same RUNTIME_EXCEPTION a real arm would send.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/string_view.h"

namespace cornerpose::ur_emulator {

// A literal argument.
struct ScriptValue {
  enum class Kind { kNumber, kBool, kString, kList, kPose };
  Kind kind = Kind::kNumber;
  double number = 0.0;           // kNumber
  bool boolean = false;          // kBool
  std::string text;              // kString
  std::vector<double> elements;  // kList (numbers only), kPose (6 numbers)

  // Text as textmsg prints it: numbers shortest form, True/False, lists and
  // poses as `[a, b]` / `p[a, b, ...]`.
  std::string ToString() const;
};

// One statement: a call of a known built-in. Arguments are bound to the
// built-in's parameter names (positional and keyword), defaults filled in.
struct ScriptCall {
  int line = 0;    // 1-based, in the program text as received
  int column = 0;  // 1-based column of the function name
  std::string function;
  std::map<std::string, ScriptValue> args;

  // Argument by parameter name; the parser guarantees required ones exist.
  const ScriptValue& arg(const std::string& name) const { return args.at(name); }
  bool has(const std::string& name) const { return args.count(name) > 0; }
};

struct ScriptProgram {
  // From `def name():`; "unnamed" for bare statements.
  std::string name;
  std::vector<ScriptCall> calls;
};

// What the controller reports for a program it cannot compile.
struct ScriptError {
  int line = 0;    // 1-based
  int column = 0;  // 1-based
  // e.g. "compile_error_name_not_found:foo:" or
  // "syntax_error_on_line:3:  movej(:".
  std::string text;
};

struct ParseResult {
  ScriptProgram program;             // valid when !error
  std::optional<ScriptError> error;  // set when the text is rejected
};

// Parses a whole program text. Rules (ur-interface.md section 1): `def
// name():` (or `sec name():`) in column 1, every body line indented by at
// least one blank, `end` in column 1 as the last non-blank line, `#`
// comments and blank lines anywhere. Text that does not start with
// def/sec is compiled as bare statements (each line one call, any indent).
// Program names must match [A-Za-z_][A-Za-z0-9_]* and are truncated to 31
// characters, as the controller does.
ParseResult ParseScript(absl::string_view text);

// The built-ins the emulator knows (for tests and error messages).
bool IsKnownFunction(absl::string_view name);

}  // namespace cornerpose::ur_emulator
