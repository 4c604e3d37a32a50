// `cornerpose detect`: runs the detector on one cloud file and writes the
// results as JSON, a coloured PLY and a PNG.
#pragma once

#include <string>
#include <vector>

namespace cornerpose::tools {

// argv holds the arguments after "detect". Returns the process exit code.
int RunDetect(const std::vector<std::string>& args);

}  // namespace cornerpose::tools
