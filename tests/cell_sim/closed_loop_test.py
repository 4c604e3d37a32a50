#!/usr/bin/env python3
"""The whole simulated cell, closed loop, through scripts/demo --no-build.

Every part is real: the cell_sim binary (UR controller emulator over TCP on
the dashboard / primary / RTDE ports, the world, the rendering camera), the
perception service over gRPC reading that camera through the virtual OpenNI2
driver, and the daemon. Time scale 20. Each case checks the cell's own
account (out/.../sim/report.json) and the daemon's log.

  closed_loop_test.py SOURCE_DIR CASE     CASE: pallet | bin | protective_stop

pallet: one layer of 12 carton_s emptied, every pick placed, no collision.
bin: a heap of 6 boxes in a bin picked until empty or until the daemon
  declines what is left; no failed pick, no collision; prints how many remain
  and the daemon's reasons.
protective_stop: one layer of 12; a protective stop is injected after the
  3rd placed box; the cell stops, the test clears it on the dashboard, and
  the cell goes on until the pallet is empty.
(A box lowered onto the pile reported as a collision: cell_world_test,
LoweringTheHeldBoxIntoThePileIsACollision.)
"""
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import threading
import time

OFFSETS = {"pallet": 400, "bin": 410, "protective_stop": 420}


def run_demo(root, case, out, args):
    env = dict(os.environ, CORNERPOSE_DEMO_PORT_OFFSET=str(OFFSETS[case]),
               CORNERPOSE_DEMO_OUT=out)
    return subprocess.Popen([os.path.join(root, "scripts/demo"), "--no-build", "--time-scale", "20",
                             "--idle-timeout", "20"] + args,
                            cwd=root, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)


def dashboard(port, command):
    with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
        f = s.makefile("rw", newline="\n")
        f.readline()  # greeting
        f.write(command + "\n")
        f.flush()
        return f.readline().strip()


def clear_protective_stop(out, port, done):
    """Waits for the daemon to report the stop, then unlocks it (the
    controller refuses for its first 5 s)."""
    log = os.path.join(out, "sim", "daemon.log")
    deadline = time.time() + 120
    while time.time() < deadline and not done.is_set():
        try:
            text = open(log).read()
        except OSError:
            text = ""
        if re.search(r"(?i)protective[ _]stop", text) and "STOPPED" in text:
            while time.time() < deadline:
                reply = dashboard(port, "unlock protective stop")
                print("test: dashboard: unlock protective stop ->", reply, flush=True)
                if "releasing" in reply.lower() or "unlocked" in reply.lower():
                    return
                time.sleep(0.3)
        time.sleep(0.2)


def main():
    root, case = sys.argv[1], sys.argv[2]
    out = tempfile.mkdtemp(prefix=f"cornerpose_closed_loop_{case}_")
    args = {"pallet": ["--layers", "1"],
            "bin": ["--scene", "bin", "--heap-boxes", "6"],
            "protective_stop": ["--layers", "1", "--protective-stop-after", "3"]}[case]
    demo = run_demo(root, case, out, args)
    done = threading.Event()
    clearer = None
    if case == "protective_stop":
        clearer = threading.Thread(target=clear_protective_stop,
                                   args=(out, 29999 + OFFSETS[case], done))
        clearer.start()
    try:
        text, _ = demo.communicate(timeout=400)
    finally:
        done.set()
        if demo.poll() is None:
            demo.kill()
    print(text)
    report = json.load(open(os.path.join(out, "sim", "report.json")))
    daemon_log = open(os.path.join(out, "sim", "daemon.log")).read()
    picks = report["picks"]
    results = [p["result"] for p in picks]
    failed = [p for p in picks if p["result"] != "placed"]
    print(f"test: {case}: {report['placed']} of {report['boxes_total']} placed, "
          f"{report['in_pile']} left, results {results}, collisions {report['collisions']}")
    ok = True

    def check(condition, message):
        nonlocal ok
        if not condition:
            print("test: FAILED:", message)
            ok = False

    check(report["collisions"] == 0, f"{report['collisions']} collisions")
    if case == "pallet":
        check(not failed, f"failed picks: {failed}")
        check(report["placed"] == report["boxes_total"] == 12,
              f"placed {report['placed']} of {report['boxes_total']}")
    elif case == "bin":
        check(not failed, f"failed picks: {failed}")
        check(report["placed"] >= 1, "nothing placed")
        check(report["placed"] + report["in_pile"] + report["dropped"] == report["boxes_total"],
              "boxes unaccounted for")
        if report["in_pile"]:
            # The daemon says why it leaves them: its last refusal notes.
            notes = [l for l in daemon_log.splitlines()
                     if "none pickable" in l or "cannot plan" in l]
            check(bool(notes), "boxes left but the daemon gave no reason")
            print(f"test: bin: {report['in_pile']} boxes left; the daemon's last reason:")
            print("  ", notes[-1] if notes else "(none)")
    elif case == "protective_stop":
        check("protective stop injected" in open(os.path.join(out, "sim", "cell_sim.log")).read(),
              "no protective stop was injected")
        check(re.search(r"(?i)protective[ _]stop", daemon_log) is not None,
              "the daemon did not report the stop")
        interrupted = [p for p in failed if p["result"] == "interrupted"]
        check(len(interrupted) == 1 and len(failed) == 1,
              f"expected one interrupted pick, got {failed}")
        check(report["placed"] == report["boxes_total"] == 12,
              f"placed {report['placed']} of {report['boxes_total']} after the stop was cleared")
    print("test:", "PASSED" if ok else "FAILED", "(logs in", out + ")")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
