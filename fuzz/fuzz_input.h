// Helpers shared by the libFuzzer harnesses: the input as a string view, a
// temporary file for readers that only take a path, and a check that turns a
// broken invariant into a crash libFuzzer reports.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/strings/string_view.h"

namespace cornerpose::fuzz {

inline absl::string_view AsText(const uint8_t* data, size_t size) {
  return absl::string_view(reinterpret_cast<const char*>(data), size);
}

// One file per process (and per harness), rewritten for every input; under
// /dev/shm when there is one, so a run is not bound by the disk.
class TempFile {
 public:
  // `name` ends with the extension the reader dispatches on, e.g. "in.pcd".
  explicit TempFile(const std::string& name);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  // Replaces the file's contents; aborts when it cannot (a broken harness,
  // not a finding in the code under test).
  void Write(const uint8_t* data, size_t size) const;
  const std::string& path() const { return path_; }

 private:
  std::string dir_;
  std::string path_;
};

// Aborts with `what` on stderr when `ok` is false: libFuzzer records the
// input as a crash.
void Require(bool ok, const char* what);

}  // namespace cornerpose::fuzz
