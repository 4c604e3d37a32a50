#include "server/sources/openni2_init.h"

#include <OpenNI.h>

#include <mutex>

#include "absl/strings/str_cat.h"

namespace cornerpose::server {

absl::Status EnsureOpenNi2Initialized() {
  static std::mutex mutex;
  static bool initialized = false;  // guarded by mutex
  std::lock_guard<std::mutex> lock(mutex);
  if (initialized) return absl::OkStatus();
  // Loading the drivers briefly changes the process's working directory
  // (OpenNI2 chdirs into its driver repository), so it happens once, here.
  if (openni::OpenNI::initialize() != openni::STATUS_OK) {
    const std::string reason = openni::OpenNI::getExtendedError();
    // OpenNI2 counts initialisations even when one fails; undo it so the
    // next attempt really loads the drivers again.
    openni::OpenNI::shutdown();
    return absl::UnavailableError(absl::StrCat("cannot initialize OpenNI2: ", reason));
  }
  initialized = true;
  return absl::OkStatus();
}

}  // namespace cornerpose::server
