// Command-line arguments of the `cornerpose` subcommands: `--key value` or
// `--key=value` for options, bare `--flag` for switches; anything else is an
// error that names the argument.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace cornerpose::tools {

struct CommandArgs {
  std::map<std::string, std::string> values;  // option -> value
  std::set<std::string> flags;                // switches given

  std::optional<std::string> Get(const std::string& key) const;
  bool Has(const std::string& flag) const { return flags.count(flag) > 0; }
  // Parse the option's value into *out when given; INVALID_ARGUMENT names
  // the option when it does not parse.
  absl::Status SetDouble(const std::string& key, double* out) const;
  absl::Status SetInt(const std::string& key, int* out) const;
  absl::Status SetBool(const std::string& key, bool* out) const;
};

// When `args` hold --help or -h, prints `help` to stdout and returns true:
// the command then exits 0 without parsing anything else.
bool PrintHelpIfAsked(const std::vector<std::string>& args, const char* help);

// `options` take a value; `switches` do not; `required` options must appear.
absl::StatusOr<CommandArgs> ParseCommandArgs(const std::vector<std::string>& args,
                                             const std::vector<std::string>& options,
                                             const std::vector<std::string>& switches,
                                             const std::vector<std::string>& required = {});

}  // namespace cornerpose::tools
