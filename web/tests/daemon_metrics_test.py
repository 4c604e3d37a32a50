"""The robot-cell daemon's /metrics (DaemonMetrics on a real HTTP port, driven by
daemon_metrics_sample) read with the Prometheus client's text parser: picks by
outcome, cycle and program time, cell state and link ages move as events happen.

  daemon_metrics_test.py DAEMON_METRICS_SAMPLE DASHBOARD_JSON

Also: every cell metric the Grafana dashboard queries is exported."""

import math
import pathlib
import subprocess
import sys
import urllib.request

from prometheus_client.parser import text_string_to_metric_families

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from live_server import dashboard_metrics  # noqa: E402


def scrape(port):
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/metrics", timeout=10) as r:
        assert r.status == 200
        assert r.headers["Content-Type"].startswith("text/plain; version=0.0.4")
        text = r.read().decode()
    families = {f.name: f for f in text_string_to_metric_families(text)}
    values = {(s.name, tuple(sorted(s.labels.items()))): s.value
              for f in families.values() for s in f.samples}
    return families, values


def v(values, name, **labels):
    return values.get((name, tuple(sorted(labels.items()))), 0.0)


sample = subprocess.Popen([sys.argv[1]], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
port = int(sample.stdout.readline().split()[1])


def send(*commands):
    for c in commands:
        sample.stdin.write(c + "\n")
        sample.stdin.flush()
        assert sample.stdout.readline().strip() == "ok"


families, before = scrape(port)
assert families["cornerpose_cell_picks"].type == "counter"  # _total stripped by the parser
assert families["cornerpose_cell_cycle_seconds"].type == "histogram"
assert families["cornerpose_cell_state"].type == "gauge"
assert v(before, "cornerpose_cell_state", state="STARTING") == 1
assert v(before, "cornerpose_cell_picks_total", outcome="COMPLETED") == 0
assert math.isinf(v(before, "cornerpose_cell_link_age_seconds", link="robot"))

send("state PICKING", "robot up", "detection", "pick COMPLETED 4.5", "pick COMPLETED 5.0",
     "pick PROTECTIVE_STOP 1.0", "robot down")
_, after = scrape(port)
assert v(after, "cornerpose_cell_picks_total", outcome="COMPLETED") == 2
assert v(after, "cornerpose_cell_picks_total", outcome="PROTECTIVE_STOP") == 1
assert v(after, "cornerpose_cell_program_seconds_count") == 3
assert v(after, "cornerpose_cell_program_seconds_sum") == 10.5
assert v(after, "cornerpose_cell_cycle_seconds_count") == 2  # between three picks
assert v(after, "cornerpose_cell_state", state="PICKING") == 1
assert v(after, "cornerpose_cell_state", state="STARTING") == 0
assert v(after, "cornerpose_cell_link_up", link="robot") == 0
robot_age = v(after, "cornerpose_cell_link_age_seconds", link="robot")
assert 0 < robot_age < 5, robot_age  # down since a moment ago
assert v(after, "cornerpose_cell_link_age_seconds", link="perception") < 5
exported = {name for (name, _) in after}
used = dashboard_metrics(pathlib.Path(sys.argv[2]), "cornerpose_cell_")
missing = {n for n in used if n not in exported and n + "_total" not in exported
           and n + "_count" not in exported}
assert used and not missing, f"the dashboard queries metrics the daemon lacks: {missing}"
sample.stdin.close()
assert sample.wait(timeout=10) == 0
print("daemon_metrics_test: parsed; picks, cycle time, state and link ages moved as asked")
