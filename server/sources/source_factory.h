// Making the FrameSource a SourceSpec describes.
#pragma once

#include <memory>
#include <vector>

#include "server/config/server_options.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// One started source per spec, in order: a DirectorySource or an
// OpenNi2Source. Never fails: a source that cannot work reports kFailed.
// OpenNI2 is initialised here, before any source thread runs, when a spec
// needs it (its driver loading briefly changes the working directory, which
// a directory source resolving a relative path must not see).
std::vector<std::unique_ptr<FrameSource>> MakeFrameSources(const std::vector<SourceSpec>& specs);

}  // namespace cornerpose::server
