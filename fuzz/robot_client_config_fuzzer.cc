// The robot-cell daemon's configuration file (robot_client/robot_config.h):
// the text format parser (common/config), the conversion and Validate().
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_input.h"
#include "robot_client/config/robot_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const cornerpose::fuzz::TempFile file("robot_client.textproto");
  file.Write(data, size);
  const absl::StatusOr<cornerpose::robot_client::RobotClientOptions> options =
      cornerpose::robot_client::LoadRobotClientConfig(file.path());
  if (!options.ok()) {
    cornerpose::fuzz::Require(absl::IsInvalidArgument(options.status()),
                              "a bad configuration is INVALID_ARGUMENT");
  } else {
    cornerpose::fuzz::Require(options->Validate().ok(), "a loaded configuration validates");
  }
  return 0;
}
