// Prints a registry holding every kind of metric, awkward label values
// included, in the text format; parse_exposition.py reads it with the
// Prometheus client's own parser.
#include <iostream>
#include <limits>

#include "common/metrics/metrics.h"

int main() {
  using namespace cornerpose::metrics;
  Registry r;
  auto& requests = *r.AddCounter("sample_requests_total", "Requests.\nSecond line \\ slash.",
                                 {"method", "code"}).value();
  requests.WithLabels({"Detect", "OK"}).Increment(7);
  requests.WithLabels({"Detect", "INVALID_ARGUMENT"}).Increment(2);
  auto& queue = *r.AddGauge("sample_queue_depth", "Queued.").value();
  queue.WithLabels({}).Set(3);
  auto& latency = *r.AddHistogram("sample_latency_seconds", "Latency.", {"stage"},
                                  DefaultSecondsBuckets()).value();
  for (double v : {0.004, 0.09, 0.12, 0.5, 40.0}) latency.WithLabels({"total"}).Observe(v);
  latency.WithLabels({"edge_points"}).Observe(0.03);
  (void)r.AddGaugeCallback("sample_frame_age_seconds", "Age.", {"source"}, [] {
    return std::vector<std::pair<LabelValues, double>>{
        {{"quote\"back\\slash\nnewline"}, 1.25},
        {{"never"}, std::numeric_limits<double>::quiet_NaN()}};
  });
  std::cout << r.Serialize();
  return 0;
}
