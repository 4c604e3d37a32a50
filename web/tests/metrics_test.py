"""The server's /metrics read with the Prometheus client's own text parser
(Debian's python3-prometheus-client), before and after requests: its counters and
histograms must move by what was asked.

  metrics_test.py SERVER CLI FRAMES_DIR FRAME DASHBOARD_JSON

Also: every server metric the Grafana dashboard queries is exported."""

import math
import pathlib
import subprocess
import sys
import tempfile
import time

from prometheus_client.parser import text_string_to_metric_families

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from live_server import LiveServer, dashboard_metrics, detect_count  # noqa: E402


def scrape(s):
    status, body = s.get("/metrics")
    assert status == 200, status
    families = {f.name: f for f in text_string_to_metric_families(body.decode())}
    values = {}
    for f in families.values():
        for sample in f.samples:
            values[(sample.name, tuple(sorted(sample.labels.items())))] = sample.value
    return families, values


def value(values, name, **labels):
    return values.get((name, tuple(sorted(labels.items()))), 0.0)


def main():
    server, cli, frames, frame, dashboard = sys.argv[1:6]
    with LiveServer(server, pathlib.Path(frames), frame) as s, \
            tempfile.TemporaryDirectory() as tmp:
        families, before = scrape(s)
        for name, kind in [("cornerpose_detections", "counter"),
                           ("cornerpose_rpcs", "counter"),
                           ("cornerpose_detection_stage_seconds", "histogram"),
                           ("cornerpose_rpc_duration_seconds", "histogram"),
                           ("cornerpose_rpcs_open", "gauge"),
                           ("cornerpose_detection_queue_depth", "gauge"),
                           ("cornerpose_source_state", "gauge"),
                           ("cornerpose_source_frame_age_seconds", "gauge"),
                           ("cornerpose_http_requests", "counter")]:
            assert families[name].type == kind, (name, families[name].type)

        # Two Detects (one OK, one for a source that does not exist) and a view detection.
        detect_count(cli, s.address, "one", "carton_s", pathlib.Path(tmp) / "d.json")
        missing = subprocess.run([str(cli), "client", "detect", "--server", s.address,
                                  "--source", "nowhere", "--box", "carton_s", "--quiet"],
                                 capture_output=True, timeout=60)
        assert missing.returncode != 0
        status, _ = s.get("/api/sources/one/latest")
        assert status == 200, status
        status, _ = s.get("/api/sources/nowhere/latest")
        assert status == 404, status

        def moved(name, **labels):
            return value(after, name, **labels) - value(before, name, **labels)

        # A call is counted when the server has finished it, which may be a
        # moment after its client has the answer (a loaded machine): an RPC when
        # its handler returns, an HTTP request when httplib's logger runs, after
        # the response is written. Scrape until the two Detects and the 404 are
        # in, for up to 10 s.
        deadline = time.monotonic() + 10.0
        while True:
            _, after = scrape(s)
            counted = moved("cornerpose_rpc_duration_seconds_count", method="Detect") >= 2 and \
                moved("cornerpose_http_requests_total", route="/api/sources/{name}/latest",
                      status="404") >= 1
            if counted or time.monotonic() > deadline:
                break
            time.sleep(0.1)

        assert moved("cornerpose_rpcs_total", method="Detect", code="OK") == 1
        assert moved("cornerpose_rpcs_total", method="Detect", code="NOT_FOUND") == 1
        assert moved("cornerpose_rpc_duration_seconds_count", method="Detect") == 2
        assert moved("cornerpose_detections_total", origin="rpc") == 1
        assert moved("cornerpose_detections_total", origin="view") >= 1
        assert moved("cornerpose_detection_stage_seconds_count", stage="total") >= 2
        assert moved("cornerpose_detection_stage_seconds_sum", stage="edge_points") > 0
        assert moved("cornerpose_http_requests_total", route="/api/sources/{name}/latest",
                     status="404") == 1
        assert moved("cornerpose_http_requests_total", route="/metrics", status="200") >= 1
        assert value(after, "cornerpose_source_state", source="one", state="RUNNING") == 1
        assert value(after, "cornerpose_source_state", source="one", state="FAILED") == 0
        age = value(after, "cornerpose_source_frame_age_seconds", source="one")
        assert math.isfinite(age) and 0 <= age < 60, age
        assert value(after, "cornerpose_rpcs_open", method="StreamDetections") == 0
        exported = {name for (name, _) in after}
        used = dashboard_metrics(pathlib.Path(dashboard), "cornerpose_")
        used = {n for n in used if not n.startswith("cornerpose_cell_")}
        missing = {n for n in used if n not in exported and n + "_total" not in exported
                   and n + "_count" not in exported}
        assert used and not missing, f"the dashboard queries metrics the server lacks: {missing}"
        print(f"metrics_test: {len(families)} families parsed; counters moved as asked")


if __name__ == "__main__":
    main()
