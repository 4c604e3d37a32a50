#include "fuzz/fuzz_input.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace cornerpose::fuzz {

TempFile::TempFile(const std::string& name) {
  const char* shm = "/dev/shm";
  std::string base = std::filesystem::is_directory(shm)
                         ? shm
                         : std::filesystem::temp_directory_path().string();
  std::string pattern = base + "/cornerpose_fuzz_XXXXXX";
  if (mkdtemp(pattern.data()) == nullptr) {
    std::perror("mkdtemp");
    std::abort();
  }
  dir_ = pattern;
  path_ = dir_ + "/" + name;
}

TempFile::~TempFile() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

void TempFile::Write(const uint8_t* data, size_t size) const {
  FILE* f = std::fopen(path_.c_str(), "wb");
  if (f == nullptr || (size > 0 && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
    std::perror(path_.c_str());
    std::abort();
  }
}

void Require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
  std::abort();
}

}  // namespace cornerpose::fuzz
