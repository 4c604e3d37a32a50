// Named box sizes, so callers can say "carton_s" instead of three numbers:
// the built-in table, and a configuration's own models before it.
#pragma once

#include <map>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/box/box_types.h"

namespace cornerpose {

// The built-in models (l x b x h, metres): brick 0.19 x 0.09 x 0.057,
// carton_s 0.30 x 0.20 x 0.15, carton_l 0.40 x 0.30 x 0.25,
// carton_sq 0.25 x 0.25 x 0.20, carton_flat 0.30 x 0.20 x 0.10.
absl::StatusOr<BoxDims> BoxModelByName(absl::string_view name);

// Box sizes by model name, besides the built-in ones (the server
// configuration's box_models).
using BoxModels = std::map<std::string, BoxDims>;

// `name` in `models` first, then a built-in model; NOT_FOUND as
// BoxModelByName when it is neither. The server resolves every request's
// box_model with it, so a name means one size everywhere.
absl::StatusOr<BoxDims> ResolveBoxModel(absl::string_view name, const BoxModels& models);

// Parses "L,B,H" in metres, or a model name; validates the result.
absl::StatusOr<BoxDims> ParseBoxDims(absl::string_view text);

}  // namespace cornerpose
