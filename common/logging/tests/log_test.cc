// Log lines in both formats; JSON lines parse back with every field.
#include "common/logging/log.h"

#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "nlohmann/json.hpp"

namespace cornerpose::logging {
namespace {

// 2024-12-01T22:41:07.512Z
constexpr int64_t kTime = 1733092867512000000;

TEST(Log, ParseLogFormat) {
  EXPECT_EQ(ParseLogFormat("text").value(), LogFormat::kText);
  EXPECT_EQ(ParseLogFormat("json").value(), LogFormat::kJson);
  const auto bad = ParseLogFormat("xml");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), ::testing::HasSubstr("\"xml\""));
}

TEST(Log, TextLine) {
  EXPECT_EQ(FormatLine(LogFormat::kText, kTime, LogLevel::kInfo, "server", "listening",
                       {{"address", "0.0.0.0:50051"}, {"port", 50051}, {"tls", false},
                        {"note", "two words"}}),
            "22:41:07.512 INFO server: listening address=0.0.0.0:50051 port=50051 tls=false "
            "note=\"two words\"");
}

TEST(Log, JsonLineParsesBackWithEveryField) {
  const std::string line =
      FormatLine(LogFormat::kJson, kTime, LogLevel::kWarning, "cell", "pick failed",
                 {{"pick_id", uint64_t{12}}, {"plan_ms", 1.25}, {"detail", "quote \" and \n"},
                  {"level", "overwrite attempt"}, {"dry_run", true}});
  EXPECT_EQ(line.find('\n'), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(line);
  EXPECT_EQ(j["time"], "2024-12-01T22:41:07.512Z");
  EXPECT_EQ(j["level"], "warning");
  EXPECT_EQ(j["component"], "cell");
  EXPECT_EQ(j["message"], "pick failed");
  EXPECT_EQ(j["pick_id"], 12);
  EXPECT_DOUBLE_EQ(j["plan_ms"].get<double>(), 1.25);
  EXPECT_EQ(j["detail"], "quote \" and \n");
  EXPECT_EQ(j["field_level"], "overwrite attempt");
  EXPECT_EQ(j["dry_run"], true);
}

TEST(Log, InvalidUtf8IsReplacedNotThrown) {
  const std::string line = FormatLine(LogFormat::kJson, kTime, LogLevel::kError, "server",
                                      "bad file", {{"path", absl::string_view("a\xff\xfe.png")}});
  EXPECT_NO_THROW(nlohmann::json::parse(line));
}

TEST(Log, LinesFromThreadsDoNotInterleave) {
  std::ostringstream out;
  SetLogStream(&out);
  SetLogFormat(LogFormat::kJson);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([t] {
      for (int i = 0; i < 200; ++i) Log(LogLevel::kInfo, "test", "line", {{"t", t}, {"i", i}});
    });
  }
  for (auto& t : threads) t.join();
  SetLogStream(nullptr);
  SetLogFormat(LogFormat::kText);
  std::istringstream lines(out.str());
  std::string line;
  int count = 0;
  while (std::getline(lines, line)) {
    const nlohmann::json j = nlohmann::json::parse(line);
    EXPECT_EQ(j["component"], "test");
    ++count;
  }
  EXPECT_EQ(count, 800);
}

}  // namespace
}  // namespace cornerpose::logging
