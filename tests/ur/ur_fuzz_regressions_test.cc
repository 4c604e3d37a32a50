// Inputs the fuzzers (fuzz/) found that the UR parsers mishandled, each fed
// to the parser again (tests/data/fuzz/).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "robot_client/ur/primary.h"

namespace cornerpose::ur {
namespace {

using ::testing::HasSubstr;

std::string ReadInput(const std::string& name) {
  std::ifstream in(std::string(CORNERPOSE_FUZZ_TEST_DATA) + "/" + name, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// ur_primary_fuzzer: the recorded UR5e ROBOT_STATE with its Cartesian
// sub-package retyped as a second robot-mode sub-package. The second
// overwrote the first, and the package re-encoded 54 bytes longer.
TEST(UrFuzzRegressionsTest, RobotStateWithARepeatedSubPackageIsRejected) {
  const std::string input = ReadInput("ur_primary_robot_state_two_robot_mode_subpackages.bin");
  ASSERT_EQ(input.size(), 1386u);
  const absl::StatusOr<PrimaryPackage> package = ParsePrimaryPackage(input);
  EXPECT_EQ(package.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(package.status().message()),
              HasSubstr("sub-package type 0 appears twice"));
}

// Sub-packages this library keeps raw may repeat: they re-encode as they came.
TEST(UrFuzzRegressionsTest, RepeatedRawSubPackagesStillRoundTrip) {
  RobotState state;
  state.other = {RawSubPackage{9, "ab"}, RawSubPackage{9, "cd"}};
  state.order = {9, 9};
  const std::string bytes = EncodeRobotState(state);
  const absl::StatusOr<PrimaryPackage> package = ParsePrimaryPackage(bytes);
  ASSERT_TRUE(package.ok()) << package.status();
  EXPECT_EQ(EncodePrimaryPackage(*package), bytes);
}

}  // namespace
}  // namespace cornerpose::ur
