// Reads the recorded controller packets in tests/data/ur.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

namespace cornerpose::ur {

inline std::string ReadTestFile(const std::string& name) {
  const std::string path = std::string(CORNERPOSE_UR_TEST_DATA) + "/" + name;
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace cornerpose::ur
