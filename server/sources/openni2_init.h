// OpenNI2's process-wide initialisation, shared by every openni2 source.
#pragma once

#include "absl/status/status.h"

namespace cornerpose::server {

// Initialises OpenNI2 (loading its drivers) the first time it succeeds;
// later calls return OK at once. Thread-safe. A failure (no drivers found,
// say) is returned as UNAVAILABLE with OpenNI2's reason and tried again on
// the next call. OpenNI2 is never shut down: sources on other threads may
// still hold devices, and the process's exit releases it.
absl::Status EnsureOpenNi2Initialized();

}  // namespace cornerpose::server
