// Prometheus metrics: counters, gauges and histograms in labelled families,
// and their text exposition format (version 0.0.4) for a /metrics endpoint.
// Debian 12 ships no C++ Prometheus client, so this is the small subset the
// server and the daemon need. Thread-safe: metrics are updated lock-free
// from any thread; a family's label map and Serialize() take a mutex.
//
//   Registry registry;
//   CounterFamily& requests = *registry.AddCounter(
//       "cornerpose_requests_total", "RPCs answered, by method and status code",
//       {"method", "code"}).value();
//   requests.WithLabels({"Detect", "OK"}).Increment();
//   std::string text = registry.Serialize();
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace cornerpose::metrics {

using LabelValues = std::vector<std::string>;

// A value that only goes up (events, seconds spent).
class Counter {
 public:
  // by >= 0; a negative or NaN increment is ignored (counters never go down).
  void Increment(double by = 1.0);
  double Value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

// A value that goes up and down (queue depth, open streams, a state).
class Gauge {
 public:
  void Set(double value) { value_.store(value, std::memory_order_relaxed); }
  void Add(double by);
  double Value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

// Observations counted into cumulative buckets (latencies, durations).
class Histogram {
 public:
  // bounds: the buckets' upper bounds, increasing and finite (+Inf is implied).
  explicit Histogram(std::vector<double> bounds);
  void Observe(double value);
  const std::vector<double>& bounds() const { return bounds_; }
  // Observations <= bounds()[i] (cumulative), and all of them at the end.
  std::vector<uint64_t> CumulativeCounts() const;
  double Sum() const { return sum_.load(std::memory_order_relaxed); }
  uint64_t Count() const { return count_.load(std::memory_order_relaxed); }

 private:
  std::vector<double> bounds_;
  std::unique_ptr<std::atomic<uint64_t>[]> buckets_;  // per bucket, not cumulative
  std::atomic<double> sum_{0.0};
  std::atomic<uint64_t> count_{0};
};

// Latency buckets in seconds, 1 ms to 30 s: a detection takes ~0.1 s, a pick
// program ~10 s.
std::vector<double> DefaultSecondsBuckets();

// The metrics of one name, one per combination of label values.
template <typename Metric>
class Family {
 public:
  Family(std::string name, std::string help, std::vector<std::string> label_names,
         std::function<std::unique_ptr<Metric>()> make)
      : name_(std::move(name)), help_(std::move(help)), label_names_(std::move(label_names)),
        make_(std::move(make)) {}

  // The metric for these label values, one per label name (missing ones
  // are empty, extra ones dropped); created at 0 on first use. The
  // reference stays valid until Remove() of the same values.
  Metric& WithLabels(const LabelValues& values);
  // Drops the metric of these values (a source that was removed).
  void Remove(const LabelValues& values);

  const std::string& name() const { return name_; }
  const std::string& help() const { return help_; }
  const std::vector<std::string>& label_names() const { return label_names_; }
  // Calls f(values, metric) for each metric, in label order, under the lock.
  void ForEach(const std::function<void(const LabelValues&, const Metric&)>& f) const;

 private:
  std::string name_;
  std::string help_;
  std::vector<std::string> label_names_;
  std::function<std::unique_ptr<Metric>()> make_;
  mutable std::mutex mutex_;
  std::map<LabelValues, std::unique_ptr<Metric>> metrics_;
};

using CounterFamily = Family<Counter>;
using GaugeFamily = Family<Gauge>;
using HistogramFamily = Family<Histogram>;

// Gauges computed when scraped (a source's frame age, its state): the
// callback returns (label values, value) pairs.
using GaugeCallback = std::function<std::vector<std::pair<LabelValues, double>>()>;

class Registry {
 public:
  // Names: [a-zA-Z_:][a-zA-Z0-9_:]*; label names [a-zA-Z_][a-zA-Z0-9_]*, not
  // starting with "__" and not "le" for histograms. INVALID_ARGUMENT naming
  // the bad name; ALREADY_EXISTS for a name registered twice.
  absl::StatusOr<CounterFamily*> AddCounter(const std::string& name, const std::string& help,
                                            std::vector<std::string> label_names = {});
  absl::StatusOr<GaugeFamily*> AddGauge(const std::string& name, const std::string& help,
                                        std::vector<std::string> label_names = {});
  absl::StatusOr<HistogramFamily*> AddHistogram(const std::string& name, const std::string& help,
                                                std::vector<std::string> label_names,
                                                std::vector<double> bounds);
  absl::Status AddGaugeCallback(const std::string& name, const std::string& help,
                                std::vector<std::string> label_names, GaugeCallback callback);

  // Every family in the Prometheus text format, in registration order.
  std::string Serialize() const;

 private:
  absl::Status CheckNew(const std::string& name, const std::vector<std::string>& label_names,
                        bool histogram) const;

  struct Entry {
    std::unique_ptr<CounterFamily> counter;
    std::unique_ptr<GaugeFamily> gauge;
    std::unique_ptr<HistogramFamily> histogram;
    std::string name, help;
    std::vector<std::string> label_names;
    GaugeCallback callback;
  };
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<Entry>> entries_;
};

// The Content-Type of Serialize()'s output.
inline constexpr char kTextFormatContentType[] = "text/plain; version=0.0.4; charset=utf-8";

}  // namespace cornerpose::metrics
