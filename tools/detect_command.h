// `cornerpose detect`: runs the detector on one cloud file and writes the
// results as JSON, a coloured PLY and a PNG.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/perception/types.h"

namespace cornerpose::tools {

// argv holds the arguments after "detect". Returns the process exit code.
int RunDetect(const std::vector<std::string>& args);

// Prints the summary line ("<label>: N points, ... boxes (T ms)") and one
// line per box, as `cornerpose detect` does (shared with `cornerpose client`).
// num_points: the cloud's size, or nullopt when it is not known here (a
// server-side frame whose cloud was not fetched).
void PrintDetection(const std::string& label, std::optional<size_t> num_points,
                    const Detection& detection);

}  // namespace cornerpose::tools
