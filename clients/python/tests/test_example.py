"""examples/best_box_pose.py as a warehouse system runs it, against the real server."""

import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import cornerpose

EXAMPLE = pathlib.Path(__file__).resolve().parent.parent / "examples" / "best_box_pose.py"


def run(*args):
    return subprocess.run([sys.executable, str(EXAMPLE), *args], capture_output=True, text=True,
                          timeout=120)


def test_prints_the_best_box_in_the_base_frame(server, repo):
    config = repo / "deploy" / "config" / "robot_client.textproto"
    out = run("--server", server.address, "--source", "one", "--box", "carton_s",
              "--robot_config", str(config), "--json")
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    with server.client() as c:
        best = c.detect(source="one", box="carton_s").best
    np.testing.assert_allclose(result["camera_T_box"], best.pose, atol=1e-9)
    # The demo cell's calibration: camera 1.3 m above the base, looking down (180 deg about x).
    base_T_camera = cornerpose.as_transform([0.0, -0.5, 1.3, 0, 1, 0, 0])
    np.testing.assert_allclose(result["base_T_box"], base_T_camera @ best.pose, atol=1e-9)
    np.testing.assert_allclose(result["grasp_point"],
                               base_T_camera[:3, :3] @ best.grasp_centre + base_T_camera[:3, 3],
                               atol=1e-9)
    # The face a suction cup takes from above points up in the base frame.
    assert result["grasp_normal"][2] > 0.9

    text = run("--server", server.address, "--source", "one", "--box", "0.30,0.20,0.15",
               "--base_pose_camera", "0,-0.5,1.3,0,1,0,0")
    assert text.returncode == 0, text.stderr
    assert "best box: score" in text.stdout
    centre = " ".join(f"{x:.4f}," for x in (base_T_camera @ best.pose)[:3, 3]).rstrip(",")
    assert f"base frame:   centre ({centre})" in text.stdout


@pytest.mark.parametrize("args,status,message", [
    (["--source", "nope", "--box", "carton_s"], 1, "NOT_FOUND"),
    (["--source", "one", "--box", "carton_s", "--base_pose_camera", "1,2,3"], 2, "transform"),
    (["--source", "one", "--box", "0.3,-0.2,0.1"], 2, "each > 0"),
])
def test_errors(server, args, status, message):
    out = run("--server", server.address, *args)
    assert out.returncode == status, out.stdout + out.stderr
    assert message in out.stderr
