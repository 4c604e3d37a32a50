"""Fixtures: a real cornerpose_server on a loopback port the OS picks, serving the
repository's bundled frames (data/frames).

Environment (set by CTest, clients/python/CMakeLists.txt):
  CORNERPOSE_SERVER      the cornerpose_server binary
  CORNERPOSE_CLI         the cornerpose command-line tool (offline detection, for comparison)
  CORNERPOSE_SOURCE_DIR  the repository root
"""

import os
import pathlib
import queue
import re
import shutil
import signal
import subprocess
import threading
import time

import pytest

import cornerpose


def _env_path(name: str) -> pathlib.Path:
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"{name} is not set (run these tests through ctest)")
    return pathlib.Path(value)


@pytest.fixture(scope="session")
def repo() -> pathlib.Path:
    return _env_path("CORNERPOSE_SOURCE_DIR")


@pytest.fixture(scope="session")
def frames(repo) -> pathlib.Path:
    return repo / "data" / "frames"


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    return _env_path("CORNERPOSE_CLI")


class RunningServer:
    """A cornerpose_server process; its gRPC address and its stderr so far."""

    def __init__(self, binary: pathlib.Path, args):
        self.process = subprocess.Popen([str(binary), "--listen", "127.0.0.1:0", *args],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                        text=True)
        self.log = []
        lines: "queue.Queue[str]" = queue.Queue()

        def pump():
            for line in self.process.stderr:
                self.log.append(line)
                lines.put(line)
            lines.put("")

        threading.Thread(target=pump, daemon=True).start()
        deadline = time.monotonic() + 60
        while True:
            try:
                line = lines.get(timeout=max(0.1, deadline - time.monotonic()))
            except queue.Empty:
                self.stop()
                pytest.fail("cornerpose_server printed no port within 60 s:\n" + "".join(self.log))
            if line == "":
                pytest.fail("cornerpose_server exited:\n" + "".join(self.log))
            match = re.search(r"listening on .*\(port (\d+)\)", line)
            if match:
                self.port = int(match.group(1))
                break
        self.address = f"127.0.0.1:{self.port}"

    def client(self, **kwargs) -> cornerpose.Client:
        return cornerpose.Client(self.address, **kwargs)

    def wait_for_state(self, source: str, state: str, timeout: float = 30.0) -> cornerpose.Source:
        with self.client() as c:
            deadline = time.monotonic() + timeout
            while True:
                found = {s.name: s for s in c.sources()}[source]
                if found.state == state or time.monotonic() > deadline:
                    return found
                time.sleep(0.05)

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        return self.process.returncode


@pytest.fixture(scope="session")
def single_frame_dir(tmp_path_factory, frames) -> pathlib.Path:
    """A recorded-frame directory holding only carton_s/heap_001, so every frame of a
    source on it is that file."""
    d = tmp_path_factory.mktemp("one_frame")
    for name in ("heap_001.png", "intrinsics.txt"):
        shutil.copy(frames / "carton_s" / name, d / name)
    return d


@pytest.fixture(scope="session")
def server(frames, single_frame_dir, tmp_path_factory):
    """Sources: carton_s (all carton frames, 10 fps, loop), one (heap_001 only),
    broken (a directory that does not exist: FAILED)."""
    missing = tmp_path_factory.mktemp("missing") / "nothing_here"
    s = RunningServer(_env_path("CORNERPOSE_SERVER"), [
        "--source", f"carton_s={frames / 'carton_s'}:10:loop",
        "--source", f"one={single_frame_dir}:10:loop",
        "--source", f"broken={missing}:5:loop",
    ])
    s.wait_for_state("carton_s", "RUNNING")
    s.wait_for_state("one", "RUNNING")
    yield s
    assert s.stop() == 0, "".join(s.log)


@pytest.fixture
def start_server():
    """Starts extra servers for one test (a source that plays once, say); stops them after."""
    started = []

    def start(*args) -> RunningServer:
        s = RunningServer(_env_path("CORNERPOSE_SERVER"), list(args))
        started.append(s)
        return s

    yield start
    for s in started:
        s.stop()
