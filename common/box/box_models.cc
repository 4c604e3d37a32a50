#include "common/box/box_models.h"

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

constexpr std::array<std::pair<absl::string_view, BoxDims>, 5> kModels = {{
    {"brick", {0.19, 0.09, 0.057}},
    {"carton_s", {0.30, 0.20, 0.15}},
    {"carton_l", {0.40, 0.30, 0.25}},
    {"carton_sq", {0.25, 0.25, 0.20}},
    {"carton_flat", {0.30, 0.20, 0.10}},
}};

}  // namespace

absl::StatusOr<BoxDims> BoxModelByName(absl::string_view name) {
  for (const auto& [model, dims] : kModels) {
    if (model == name) return dims;
  }
  std::string known;
  for (const auto& [model, dims] : kModels)
    absl::StrAppend(&known, known.empty() ? "" : ", ", model);
  return absl::NotFoundError(
      absl::StrCat("unknown box model ", QuotedName(name), " (known: ", known, ")"));
}

absl::StatusOr<BoxDims> ResolveBoxModel(absl::string_view name, const BoxModels& models) {
  if (auto it = models.find(std::string(name)); it != models.end()) return it->second;
  return BoxModelByName(name);
}

absl::StatusOr<BoxDims> ParseBoxDims(absl::string_view text) {
  const std::vector<std::string> parts = absl::StrSplit(text, ',');
  if (parts.size() == 1) {
    absl::StatusOr<BoxDims> model = BoxModelByName(absl::StripAsciiWhitespace(text));
    if (!model.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(
          "box '", text,
          "' is neither L,B,H in metres nor a model name: ", model.status().message()));
    }
    return model;
  }
  if (parts.size() != 3) {
    return absl::InvalidArgumentError(absl::StrCat("box '", text, "' must be L,B,H in metres"));
  }
  double v[3];
  for (int i = 0; i < 3; ++i) {
    if (!absl::SimpleAtod(absl::StripAsciiWhitespace(parts[i]), &v[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat("box '", text, "': '", parts[i], "' is not a number"));
    }
  }
  BoxDims dims{v[0], v[1], v[2]};
  if (absl::Status s = dims.Validate(); !s.ok()) return s;
  return dims;
}

}  // namespace cornerpose
