#include "tools/command_args.h"

#include <algorithm>
#include <cstdio>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace cornerpose::tools {

bool PrintHelpIfAsked(const std::vector<std::string>& args, const char* help) {
  for (const std::string& a : args) {
    if (a == "--help" || a == "-h") {
      std::fputs(help, stdout);
      return true;
    }
  }
  return false;
}
namespace {

bool Contains(const std::vector<std::string>& list, const std::string& s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

}  // namespace

std::optional<std::string> CommandArgs::Get(const std::string& key) const {
  auto it = values.find(key);
  return it == values.end() ? std::nullopt : std::optional<std::string>(it->second);
}

absl::Status CommandArgs::SetDouble(const std::string& key, double* out) const {
  const std::optional<std::string> v = Get(key);
  if (v && !absl::SimpleAtod(*v, out)) {
    return absl::InvalidArgumentError(absl::StrCat("--", key, " '", *v, "' is not a number"));
  }
  return absl::OkStatus();
}

absl::Status CommandArgs::SetInt(const std::string& key, int* out) const {
  const std::optional<std::string> v = Get(key);
  if (v && !absl::SimpleAtoi(*v, out)) {
    return absl::InvalidArgumentError(absl::StrCat("--", key, " '", *v, "' is not an integer"));
  }
  return absl::OkStatus();
}

absl::Status CommandArgs::SetBool(const std::string& key, bool* out) const {
  const std::optional<std::string> v = Get(key);
  if (v && !absl::SimpleAtob(*v, out)) {
    return absl::InvalidArgumentError(absl::StrCat("--", key, " '", *v, "' is not true/false"));
  }
  return absl::OkStatus();
}

absl::StatusOr<CommandArgs> ParseCommandArgs(const std::vector<std::string>& args,
                                             const std::vector<std::string>& options,
                                             const std::vector<std::string>& switches,
                                             const std::vector<std::string>& required) {
  CommandArgs out;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i].rfind("--", 0) != 0) {
      return absl::InvalidArgumentError(absl::StrCat("unexpected argument '", args[i], "'"));
    }
    std::string key = args[i].substr(2);
    if (Contains(switches, key)) {
      out.flags.insert(key);
      continue;
    }
    std::string value;
    if (const size_t eq = key.find('='); eq != std::string::npos) {
      value = key.substr(eq + 1);
      key = key.substr(0, eq);
    } else if (Contains(options, key) && i + 1 < args.size()) {
      value = args[++i];
    } else if (Contains(options, key)) {
      return absl::InvalidArgumentError(absl::StrCat("option --", key, " needs a value"));
    }
    if (!Contains(options, key)) {
      return absl::InvalidArgumentError(absl::StrCat("unknown option --", key));
    }
    out.values[key] = value;
  }
  for (const std::string& r : required) {
    if (!out.values.count(r))
      return absl::InvalidArgumentError(absl::StrCat("--", r, " is required"));
  }
  return out;
}

}  // namespace cornerpose::tools
