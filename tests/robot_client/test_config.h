// Helpers of the robot_client tests: the shipped configuration file and
// variants of it written to temporary files.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cornerpose::robot_client::testing {

inline std::string ShippedConfigPath() {
  return (std::filesystem::path(CORNERPOSE_SOURCE_DIR) / "deploy/config/robot_client.textproto")
      .string();
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Writes `text` to a fresh file under the test temporary directory.
inline std::string WriteTempFile(const std::string& name, const std::string& text) {
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "robot_client_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  return path;
}

}  // namespace cornerpose::robot_client::testing
