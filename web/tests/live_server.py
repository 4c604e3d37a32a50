"""A real cornerpose_server on loopback replaying one recorded frame, for the web
view's tests (run_view_test.py, metrics_test.py): free gRPC and HTTP ports read
back from its JSON log lines."""

import json
import pathlib
import queue
import shutil
import signal
import subprocess
import tempfile
import threading
import time
import urllib.error
import urllib.request


class LiveServer:
    """cornerpose_server with the source `one`: FRAME.png of FRAMES, looped."""

    def __init__(self, binary, frames: pathlib.Path, frame: str, fps: float = 2.0, extra=()):
        self.dir = pathlib.Path(tempfile.mkdtemp(prefix="cornerpose_web_"))
        for name in (f"{frame}.png", "intrinsics.txt"):
            shutil.copy(frames / name, self.dir / name)
        self.log = []
        self.process = subprocess.Popen(
            [str(binary), "--listen", "127.0.0.1:0", "--http_listen", "127.0.0.1:0",
             "--log_format", "json", "--source", f"one={self.dir}:{fps}:loop", *extra],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines: "queue.Queue[str]" = queue.Queue()

        def pump():
            for line in self.process.stderr:
                self.log.append(line)
                lines.put(line)
            lines.put("")

        threading.Thread(target=pump, daemon=True).start()
        self.port = self.http_port = None
        deadline = time.monotonic() + 60
        while self.port is None or self.http_port is None:
            try:
                line = lines.get(timeout=max(0.1, deadline - time.monotonic()))
            except queue.Empty:
                self.stop()
                raise RuntimeError("cornerpose_server printed no ports in 60 s:\n" + "".join(self.log))
            if line == "":
                raise RuntimeError("cornerpose_server exited:\n" + "".join(self.log))
            entry = json.loads(line)  # every line is one JSON object
            if entry["message"].startswith("listening on"):
                self.port = entry["port"]
            elif entry["message"].startswith("http listening on"):
                self.http_port = entry["port"]
        self.address = f"127.0.0.1:{self.port}"
        self.url = f"http://127.0.0.1:{self.http_port}"

    def get(self, path: str):
        """(status, body bytes) of GET path on the HTTP port."""
        try:
            with urllib.request.urlopen(self.url + path, timeout=30) as response:
                return response.status, response.read()
        except urllib.error.HTTPError as e:
            return e.code, e.read()

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        shutil.rmtree(self.dir, ignore_errors=True)
        return self.process.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def detect_count(cli, address: str, source: str, box: str, out: pathlib.Path) -> int:
    """Boxes a gRPC Detect on the source's newest frame finds (`cornerpose client detect`)."""
    # A deadline well past the CLI's default 10 s: under a loaded test run the
    # request may queue behind the web view's own detections.
    subprocess.run([str(cli), "client", "detect", "--server", address, "--source", source,
                    "--box", box, "--json", str(out), "--quiet", "--deadline_ms", "60000"],
                   check=True, timeout=120)
    return len(json.loads(out.read_text())["boxes"])


def dashboard_metrics(path: pathlib.Path, prefix: str):
    """The metric names (as exported: cornerpose_..., without _bucket/_sum/_count)
    that the Grafana dashboard's queries use, of those starting with `prefix`."""
    import re
    names = set()
    for panel in json.loads(path.read_text())["panels"]:
        for target in panel.get("targets", []):
            for name in re.findall(r"\b(cornerpose_[a-z_]+)", target["expr"]):
                names.add(re.sub(r"_(bucket|sum|count)$", "", name))
    return {n for n in names if n.startswith(prefix)}
