// cornerpose_server's configuration file (server/server_config.h): the text
// format parser (common/config) and every range check on the values.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_input.h"
#include "server/config/server_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const cornerpose::fuzz::TempFile file("server.textproto");
  file.Write(data, size);
  const absl::StatusOr<cornerpose::server::ServerOptions> options =
      cornerpose::server::LoadServerConfig(file.path());
  if (!options.ok()) {
    cornerpose::fuzz::Require(absl::IsInvalidArgument(options.status()),
                              "a bad configuration is INVALID_ARGUMENT");
  }
  return 0;
}
