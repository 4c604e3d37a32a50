#include "common/metrics/metrics.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace cornerpose::metrics {
namespace {

void AtomicAdd(std::atomic<double>& target, double by) {
  double old = target.load(std::memory_order_relaxed);
  while (!target.compare_exchange_weak(old, old + by, std::memory_order_relaxed)) {
  }
}

bool ValidName(const std::string& name, bool colons) {
  if (name.empty()) return false;
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' ||
                        (colons && c == ':');
    if (!letter && !(i > 0 && c >= '0' && c <= '9')) return false;
  }
  return true;
}

// Shortest text that reads back as the same double; +Inf, -Inf, NaN as
// Prometheus spells them.
std::string FormatValue(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
  return std::string(buffer, result.ptr);
}

// Label values escape backslash, double quote and newline; HELP text
// escapes backslash and newline.
std::string Escape(const std::string& text, bool quotes) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '"' && quotes) {
      out += "\\\"";
    } else {
      out += c;
    }
  }
  return out;
}

std::string Labels(const std::vector<std::string>& names, const LabelValues& values,
                   const std::string& extra_name = "", const std::string& extra_value = "") {
  std::string out;
  for (size_t i = 0; i < names.size() && i < values.size(); ++i) {
    absl::StrAppend(&out, out.empty() ? "" : ",", names[i], "=\"", Escape(values[i], true), "\"");
  }
  if (!extra_name.empty()) {
    absl::StrAppend(&out, out.empty() ? "" : ",", extra_name, "=\"", extra_value, "\"");
  }
  return out.empty() ? "" : absl::StrCat("{", out, "}");
}

void Header(std::string* out, const std::string& name, const std::string& help,
            const char* type) {
  absl::StrAppend(out, "# HELP ", name, " ", Escape(help, false), "\n# TYPE ", name, " ", type,
                  "\n");
}

}  // namespace

void Counter::Increment(double by) {
  if (by > 0) AtomicAdd(value_, by);
}

void Gauge::Add(double by) { AtomicAdd(value_, by); }

Histogram::Histogram(std::vector<double> bounds)
    : bounds_(std::move(bounds)), buckets_(new std::atomic<uint64_t>[bounds_.size() + 1]) {
  for (size_t i = 0; i <= bounds_.size(); ++i) buckets_[i].store(0);
}

void Histogram::Observe(double value) {
  if (std::isnan(value)) return;
  const size_t i = std::lower_bound(bounds_.begin(), bounds_.end(), value) - bounds_.begin();
  buckets_[i].fetch_add(1, std::memory_order_relaxed);
  AtomicAdd(sum_, value);
  count_.fetch_add(1, std::memory_order_relaxed);
}

std::vector<uint64_t> Histogram::CumulativeCounts() const {
  std::vector<uint64_t> counts(bounds_.size() + 1);
  uint64_t running = 0;
  for (size_t i = 0; i <= bounds_.size(); ++i) {
    running += buckets_[i].load(std::memory_order_relaxed);
    counts[i] = running;
  }
  return counts;
}

std::vector<double> DefaultSecondsBuckets() {
  return {0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3,
          0.5,   0.75,   1.0,   2.5,  5.0,   10.0, 15.0,  20.0, 30.0};
}

template <typename Metric>
Metric& Family<Metric>::WithLabels(const LabelValues& values) {
  // One value per label name: missing ones are empty, extra ones dropped.
  LabelValues key = values;
  key.resize(label_names_.size());
  std::lock_guard<std::mutex> lock(mutex_);
  std::unique_ptr<Metric>& slot = metrics_[key];
  if (!slot) slot = make_();
  return *slot;
}

template <typename Metric>
void Family<Metric>::Remove(const LabelValues& values) {
  LabelValues key = values;
  key.resize(label_names_.size());
  std::lock_guard<std::mutex> lock(mutex_);
  metrics_.erase(key);
}

template <typename Metric>
void Family<Metric>::ForEach(
    const std::function<void(const LabelValues&, const Metric&)>& f) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [values, metric] : metrics_) f(values, *metric);
}

template class Family<Counter>;
template class Family<Gauge>;
template class Family<Histogram>;

absl::Status Registry::CheckNew(const std::string& name,
                                const std::vector<std::string>& label_names,
                                bool histogram) const {
  if (!ValidName(name, /*colons=*/true)) {
    return absl::InvalidArgumentError(absl::StrCat("metric name \"", name,
                                                   "\" is not [a-zA-Z_:][a-zA-Z0-9_:]*"));
  }
  for (const std::string& label : label_names) {
    if (!ValidName(label, /*colons=*/false) || label.rfind("__", 0) == 0 ||
        (histogram && label == "le")) {
      return absl::InvalidArgumentError(
          absl::StrCat("metric ", name, ": label name \"", label,
                       "\" is not [a-zA-Z_][a-zA-Z0-9_]* (nor __*, nor le on a histogram)"));
    }
  }
  for (const auto& entry : entries_) {
    if (entry->name == name) {
      return absl::AlreadyExistsError(absl::StrCat("metric ", name, " is registered twice"));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<CounterFamily*> Registry::AddCounter(const std::string& name,
                                                    const std::string& help,
                                                    std::vector<std::string> label_names) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (absl::Status s = CheckNew(name, label_names, false); !s.ok()) return s;
  auto entry = std::make_unique<Entry>();
  entry->name = name;
  entry->counter = std::make_unique<CounterFamily>(name, help, std::move(label_names),
                                                   [] { return std::make_unique<Counter>(); });
  CounterFamily* family = entry->counter.get();
  entries_.push_back(std::move(entry));
  return family;
}

absl::StatusOr<GaugeFamily*> Registry::AddGauge(const std::string& name, const std::string& help,
                                                std::vector<std::string> label_names) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (absl::Status s = CheckNew(name, label_names, false); !s.ok()) return s;
  auto entry = std::make_unique<Entry>();
  entry->name = name;
  entry->gauge = std::make_unique<GaugeFamily>(name, help, std::move(label_names),
                                               [] { return std::make_unique<Gauge>(); });
  GaugeFamily* family = entry->gauge.get();
  entries_.push_back(std::move(entry));
  return family;
}

absl::StatusOr<HistogramFamily*> Registry::AddHistogram(const std::string& name,
                                                        const std::string& help,
                                                        std::vector<std::string> label_names,
                                                        std::vector<double> bounds) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (absl::Status s = CheckNew(name, label_names, true); !s.ok()) return s;
  if (bounds.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("histogram ", name, ": no bucket bounds"));
  }
  for (size_t i = 0; i < bounds.size(); ++i) {
    if (!std::isfinite(bounds[i]) || (i > 0 && !(bounds[i] > bounds[i - 1]))) {
      return absl::InvalidArgumentError(absl::StrCat(
          "histogram ", name, ": bucket bound ", i, " = ", FormatValue(bounds[i]),
          " is not finite and above the previous one"));
    }
  }
  auto entry = std::make_unique<Entry>();
  entry->name = name;
  entry->histogram = std::make_unique<HistogramFamily>(
      name, help, std::move(label_names), [bounds] { return std::make_unique<Histogram>(bounds); });
  HistogramFamily* family = entry->histogram.get();
  entries_.push_back(std::move(entry));
  return family;
}

absl::Status Registry::AddGaugeCallback(const std::string& name, const std::string& help,
                                        std::vector<std::string> label_names,
                                        GaugeCallback callback) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (absl::Status s = CheckNew(name, label_names, false); !s.ok()) return s;
  auto entry = std::make_unique<Entry>();
  entry->name = name;
  entry->help = help;
  entry->label_names = std::move(label_names);
  entry->callback = std::move(callback);
  entries_.push_back(std::move(entry));
  return absl::OkStatus();
}

std::string Registry::Serialize() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string out;
  for (const auto& entry : entries_) {
    if (entry->counter) {
      const CounterFamily& f = *entry->counter;
      Header(&out, f.name(), f.help(), "counter");
      f.ForEach([&](const LabelValues& values, const Counter& c) {
        absl::StrAppend(&out, f.name(), Labels(f.label_names(), values), " ",
                        FormatValue(c.Value()), "\n");
      });
    } else if (entry->gauge) {
      const GaugeFamily& f = *entry->gauge;
      Header(&out, f.name(), f.help(), "gauge");
      f.ForEach([&](const LabelValues& values, const Gauge& g) {
        absl::StrAppend(&out, f.name(), Labels(f.label_names(), values), " ",
                        FormatValue(g.Value()), "\n");
      });
    } else if (entry->histogram) {
      const HistogramFamily& f = *entry->histogram;
      Header(&out, f.name(), f.help(), "histogram");
      f.ForEach([&](const LabelValues& values, const Histogram& h) {
        const std::vector<uint64_t> counts = h.CumulativeCounts();
        for (size_t i = 0; i < counts.size(); ++i) {
          const std::string le = i < h.bounds().size() ? FormatValue(h.bounds()[i]) : "+Inf";
          absl::StrAppend(&out, f.name(), "_bucket", Labels(f.label_names(), values, "le", le),
                          " ", counts[i], "\n");
        }
        absl::StrAppend(&out, f.name(), "_sum", Labels(f.label_names(), values), " ",
                        FormatValue(h.Sum()), "\n");
        absl::StrAppend(&out, f.name(), "_count", Labels(f.label_names(), values), " ",
                        counts.back(), "\n");
      });
    } else {
      Header(&out, entry->name, entry->help, "gauge");
      for (const auto& [values, value] : entry->callback()) {
        absl::StrAppend(&out, entry->name, Labels(entry->label_names, values), " ",
                        FormatValue(value), "\n");
      }
    }
  }
  return out;
}

}  // namespace cornerpose::metrics
