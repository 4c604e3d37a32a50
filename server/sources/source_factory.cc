#include "server/sources/source_factory.h"

#include <algorithm>
#include <iostream>

#include "server/sources/directory_source.h"
#include "server/sources/openni2_init.h"
#include "server/sources/openni2_source.h"

namespace cornerpose::server {

std::vector<std::unique_ptr<FrameSource>> MakeFrameSources(const std::vector<SourceSpec>& specs) {
  const bool openni2 = std::any_of(specs.begin(), specs.end(), [](const SourceSpec& spec) {
    return spec.kind != SourceKind::kDirectory;
  });
  if (openni2) {
    // On failure the sources report it (and retry); nothing else to do here.
    if (absl::Status s = EnsureOpenNi2Initialized(); !s.ok()) std::cerr << s.message() << "\n";
  }
  std::vector<std::unique_ptr<FrameSource>> sources;
  for (const SourceSpec& spec : specs) {
    switch (spec.kind) {
      case SourceKind::kDirectory:
        sources.push_back(std::make_unique<DirectorySource>(
            spec.name, spec.directory, DirectorySourceOptions{.fps = spec.fps, .loop = spec.loop}));
        break;
      case SourceKind::kOpenNi2Device:
        sources.push_back(std::make_unique<OpenNi2Source>(spec.name, spec.uri));
        break;
      case SourceKind::kOniFile:
        sources.push_back(std::make_unique<OpenNi2Source>(
            spec.name, spec.uri,
            OpenNi2SourceOptions{
                .recording = true, .loop = spec.loop, .playback_speed = spec.playback_speed}));
        break;
    }
  }
  return sources;
}

}  // namespace cornerpose::server
