// The metrics registry and its text exposition (format 0.0.4).
#include "common/metrics/metrics.h"

#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace cornerpose::metrics {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(Metrics, CounterGaugeHistogramValues) {
  Counter c;
  c.Increment();
  c.Increment(2.5);
  c.Increment(-4);  // ignored: counters never go down
  c.Increment(std::nan(""));
  EXPECT_DOUBLE_EQ(c.Value(), 3.5);
  Gauge g;
  g.Set(4);
  g.Add(-1.5);
  EXPECT_DOUBLE_EQ(g.Value(), 2.5);
  Histogram h({0.1, 0.5, 1.0});
  for (double v : {0.05, 0.1, 0.3, 0.7, 2.0, 3.0}) h.Observe(v);
  EXPECT_EQ(h.CumulativeCounts(), (std::vector<uint64_t>{2, 3, 4, 6}));
  EXPECT_EQ(h.Count(), 6u);
  EXPECT_DOUBLE_EQ(h.Sum(), 6.15);
}

TEST(Metrics, ConcurrentIncrementsAllCount) {
  Counter c;
  Histogram h({1.0});
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 10000; ++i) {
        c.Increment();
        h.Observe(0.5);
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_DOUBLE_EQ(c.Value(), 40000);
  EXPECT_EQ(h.Count(), 40000u);
  EXPECT_DOUBLE_EQ(h.Sum(), 20000);
}

TEST(Metrics, SerializeTextFormat) {
  Registry r;
  CounterFamily& requests =
      *r.AddCounter("cornerpose_requests_total", "RPCs answered.", {"method", "code"}).value();
  requests.WithLabels({"Detect", "OK"}).Increment(3);
  requests.WithLabels({"Detect", "NOT_FOUND"}).Increment();
  GaugeFamily& streams = *r.AddGauge("cornerpose_open_streams", "Streams open now.").value();
  streams.WithLabels({}).Set(2);
  HistogramFamily& latency =
      *r.AddHistogram("cornerpose_detection_seconds", "Detection time.", {"stage"}, {0.1, 1})
           .value();
  latency.WithLabels({"total"}).Observe(0.25);
  ASSERT_TRUE(r.AddGaugeCallback("cornerpose_source_frame_age_seconds", "Newest frame's age.",
                                 {"source"}, [] {
                                   return std::vector<std::pair<LabelValues, double>>{
                                       {{"cell"}, 0.5},
                                       {{"odd \"name\"\\\n"}, std::numeric_limits<double>::infinity()}};
                                 })
                  .ok());
  const std::string text = r.Serialize();
  EXPECT_EQ(text,
            "# HELP cornerpose_requests_total RPCs answered.\n"
            "# TYPE cornerpose_requests_total counter\n"
            "cornerpose_requests_total{method=\"Detect\",code=\"NOT_FOUND\"} 1\n"
            "cornerpose_requests_total{method=\"Detect\",code=\"OK\"} 3\n"
            "# HELP cornerpose_open_streams Streams open now.\n"
            "# TYPE cornerpose_open_streams gauge\n"
            "cornerpose_open_streams 2\n"
            "# HELP cornerpose_detection_seconds Detection time.\n"
            "# TYPE cornerpose_detection_seconds histogram\n"
            "cornerpose_detection_seconds_bucket{stage=\"total\",le=\"0.1\"} 0\n"
            "cornerpose_detection_seconds_bucket{stage=\"total\",le=\"1\"} 1\n"
            "cornerpose_detection_seconds_bucket{stage=\"total\",le=\"+Inf\"} 1\n"
            "cornerpose_detection_seconds_sum{stage=\"total\"} 0.25\n"
            "cornerpose_detection_seconds_count{stage=\"total\"} 1\n"
            "# HELP cornerpose_source_frame_age_seconds Newest frame's age.\n"
            "# TYPE cornerpose_source_frame_age_seconds gauge\n"
            "cornerpose_source_frame_age_seconds{source=\"cell\"} 0.5\n"
            "cornerpose_source_frame_age_seconds{source=\"odd \\\"name\\\"\\\\\\n\"} +Inf\n");
  requests.Remove({"Detect", "OK"});
  EXPECT_THAT(r.Serialize(), Not(HasSubstr("code=\"OK\"")));
}

TEST(Metrics, LabelValuesArePaddedToTheLabelNames) {
  Registry r;
  CounterFamily& f = *r.AddCounter("x_total", "x", {"a", "b"}).value();
  f.WithLabels({"1"}).Increment();
  f.WithLabels({"1", "", "extra"}).Increment();
  EXPECT_THAT(r.Serialize(), HasSubstr("x_total{a=\"1\",b=\"\"} 2\n"));
}

TEST(Metrics, BadNamesAreRejectedWithTheName) {
  Registry r;
  auto bad = r.AddCounter("1st", "x");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("\"1st\""));
  EXPECT_FALSE(r.AddGauge("ok_name", "x", {"bad-label"}).ok());
  EXPECT_FALSE(r.AddGauge("ok_name2", "x", {"__reserved"}).ok());
  EXPECT_FALSE(r.AddHistogram("h", "x", {"le"}, {1}).ok());
  EXPECT_FALSE(r.AddHistogram("h2", "x", {}, {}).ok());
  EXPECT_FALSE(r.AddHistogram("h3", "x", {}, {1, 1}).ok());
  EXPECT_FALSE(r.AddHistogram("h4", "x", {}, {std::nan("")}).ok());
  ASSERT_TRUE(r.AddCounter("dup_total", "x").ok());
  EXPECT_EQ(r.AddGauge("dup_total", "x").status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_TRUE(r.AddCounter("ns:sub_total", "colons are allowed in names").ok());
}

}  // namespace
}  // namespace cornerpose::metrics
