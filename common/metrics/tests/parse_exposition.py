"""Reads exposition_sample's output with the Prometheus Python client's text parser
(Debian's python3-prometheus-client) and checks every family and value."""

import math
import subprocess
import sys

from prometheus_client.parser import text_string_to_metric_families

text = subprocess.run([sys.argv[1]], check=True, capture_output=True, text=True).stdout
families = {f.name: f for f in text_string_to_metric_families(text)}


def samples(name):
    return {(s.name, tuple(sorted(s.labels.items()))): s.value for s in families[name].samples}


assert families["sample_requests"].type == "counter", families["sample_requests"].type
assert families["sample_requests"].documentation == "Requests.\nSecond line \\ slash."
req = samples("sample_requests")
assert req[("sample_requests_total", (("code", "OK"), ("method", "Detect")))] == 7
assert req[("sample_requests_total", (("code", "INVALID_ARGUMENT"), ("method", "Detect")))] == 2

assert families["sample_queue_depth"].type == "gauge"
assert samples("sample_queue_depth")[("sample_queue_depth", ())] == 3

h = families["sample_latency_seconds"]
assert h.type == "histogram"
lat = samples("sample_latency_seconds")
total = (("stage", "total"),)
assert lat[("sample_latency_seconds_count", total)] == 5
assert lat[("sample_latency_seconds_bucket", (("le", "0.1"), ("stage", "total")))] == 2
assert lat[("sample_latency_seconds_bucket", (("le", "+Inf"), ("stage", "total")))] == 5
assert abs(lat[("sample_latency_seconds_sum", total)] - 40.714) < 1e-9
assert lat[("sample_latency_seconds_count", (("stage", "edge_points"),))] == 1

age = samples("sample_frame_age_seconds")
assert age[("sample_frame_age_seconds", (("source", "quote\"back\\slash\nnewline"),))] == 1.25
assert math.isnan(age[("sample_frame_age_seconds", (("source", "never"),))])
print(f"parse_exposition: {len(families)} families parsed and checked")
