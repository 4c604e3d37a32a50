#include "server/sources/frame_source.h"

namespace cornerpose::server {

const char* SourceStateName(SourceState state) {
  switch (state) {
    case SourceState::kStarting:
      return "STARTING";
    case SourceState::kRunning:
      return "RUNNING";
    case SourceState::kFailed:
      return "FAILED";
    case SourceState::kFinished:
      return "FINISHED";
  }
  return "UNKNOWN";
}

}  // namespace cornerpose::server
