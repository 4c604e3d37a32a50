"""The client against a real cornerpose_server on loopback (see conftest.py)."""

import json
import subprocess
import time

import numpy as np
import pytest

import cornerpose

KINECT = "640,480,525,525,319.5,239.5"


def assert_same_boxes(a, b, atol_m=1e-6, atol_rot=1e-6):
    assert len(a.boxes) == len(b.boxes)
    for x, y in zip(a.boxes, b.boxes):
        np.testing.assert_allclose(x.pose[:3, 3], y.pose[:3, 3], atol=atol_m)
        np.testing.assert_allclose(x.pose[:3, :3], y.pose[:3, :3], atol=atol_rot)
        assert x.score == pytest.approx(y.score, abs=1e-3)
        assert x.grasp_face == y.grasp_face


@pytest.fixture(scope="module")
def client(server):
    with server.client() as c:
        yield c


@pytest.fixture(scope="module")
def heap(client):
    """A detection of carton_s/heap_001 through the source "one", with its cloud."""
    return client.detect(source="one", box="carton_s", include_cloud=True)


def test_health(client):
    assert client.health() == "SERVING"
    assert client.health("no.such.Service") == "SERVICE_UNKNOWN"


def test_sources(client):
    sources = {s.name: s for s in client.sources()}
    assert set(sources) == {"carton_s", "one", "broken"}
    assert sources["carton_s"].state == "RUNNING"
    assert "carton_s" in sources["carton_s"].description
    assert sources["broken"].state == "FAILED"
    assert sources["broken"].state_reason


def test_detect_on_source_equals_offline_tool(heap, cli, frames, tmp_path):
    """The boxes, poses as 4x4 matrices included, are the offline tool's on the same file."""
    out = tmp_path / "heap_001.json"
    subprocess.run([str(cli), "detect", "--cloud", str(frames / "carton_s" / "heap_001.png"),
                    "--intrinsics", KINECT, "--box", "carton_s", "--json", str(out)],
                   check=True, capture_output=True, timeout=120)
    offline = json.loads(out.read_text())
    assert len(heap.boxes) == len(offline["boxes"]) > 0
    for box, expected in zip(heap.boxes, offline["boxes"]):
        np.testing.assert_allclose(box.pose, np.array(expected["camera_T_box"]), atol=1e-5)
        assert box.score == pytest.approx(expected["score"], abs=1e-4)
        assert box.grasp_face == expected["grasp_face"]
        np.testing.assert_allclose(box.grasp_centre, expected["grasp_centre"], atol=1e-5)
    assert len(heap.segments) == len(offline["edges"])
    assert heap.corners.shape == (len(offline["corners"]), 3)


def test_detection_fields(heap, frames):
    assert heap.source == "one" and heap.frame_id > 0
    assert abs(heap.capture_time_unix_nanos / 1e9 - time.time()) < 600
    assert heap.cloud.shape == (480, 640, 3) and heap.cloud.dtype == np.float32
    assert heap.timings.total_ms > 0
    assert heap.timings.total_ms >= heap.timings.edge_points_ms
    assert heap.edge_points.shape == (0, 3)
    for box in heap.boxes:
        r = box.pose[:3, :3]
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-9)
        np.testing.assert_allclose(box.pose[3], [0, 0, 0, 1])
        assert 0 < box.score <= 1
    scores = [b.score for b in heap.boxes]
    assert scores == sorted(scores, reverse=True)
    # The best box is one of the frame's real boxes (ground truth shipped with the frame).
    truth = json.loads((frames / "carton_s" / "heap_001.json").read_text())
    centres = np.array([np.array(b["T_cam_box"])[:3, 3] for b in truth["boxes"]])
    assert np.linalg.norm(centres - heap.best.position, axis=1).min() < 0.02


def test_cloud_and_depth_inputs_give_the_source_boxes(client, heap):
    """The frame sent back as an organized cloud, an unorganized cloud and a depth image
    (the PNG's millimetres, recovered from the cloud) gives the source's boxes."""
    organized = client.detect(heap.cloud, box="carton_s", intrinsics=KINECT)
    assert_same_boxes(organized, heap)
    finite = heap.cloud.reshape(-1, 3)
    finite = finite[np.isfinite(finite).all(axis=1)]
    unorganized = client.detect(finite, box=(0.30, 0.20, 0.15), intrinsics=KINECT)
    assert_same_boxes(unorganized, heap, atol_m=1e-3, atol_rot=1e-2)
    z = heap.cloud[..., 2]
    depth = np.where(np.isfinite(z), np.round(z * 1000), 0).astype(np.uint16)
    from_depth = client.detect(depth=depth, intrinsics=KINECT, box="carton_s")
    assert_same_boxes(from_depth, heap, atol_m=1e-5, atol_rot=1e-5)
    from_metres = client.detect(depth=depth.astype(np.float32) / 1000, intrinsics=KINECT,
                                box="carton_s")
    assert_same_boxes(from_metres, heap, atol_m=1e-4, atol_rot=1e-4)
    # The client's own back-projection agrees with the server's.
    local = client.detect(cornerpose.Intrinsics.parse(KINECT).depth_to_cloud(depth), box="carton_s",
                          intrinsics=KINECT)
    assert_same_boxes(local, heap, atol_m=1e-4, atol_rot=1e-4)


def test_overrides_and_edge_points(client, heap):
    with_points = client.detect(source="one", box="carton_s", include_edge_points=True)
    assert with_points.edge_points.shape[0] > 100 and with_points.edge_points.shape[1] == 3
    stricter = client.detect(source="one", box="carton_s", edge_threshold=0.9,
                             include_edge_points=True)
    assert stricter.edge_points.shape[0] < with_points.edge_points.shape[0]


def test_stream_yields_newer_frames(server, client):
    seen = []
    with client.stream("carton_s", "carton_s", timeout=120) as stream:
        for detection in stream:
            seen.append(detection)
            if len(seen) == 3:
                break
    ids = [d.frame_id for d in seen]
    assert ids == sorted(ids) and len(set(ids)) == 3
    assert all(d.source == "carton_s" and d.cloud is None for d in seen)
    assert client.health() == "SERVING"


def test_stream_of_a_once_source_ends(start_server, frames):
    s = start_server("--source", f"brick={frames / 'brick'}:4:once")
    with s.client() as c:
        detections = list(c.stream("brick", "brick", include_cloud=True, timeout=120))
        assert 1 <= len(detections) <= 3
        assert all(d.cloud is not None and d.cloud.shape == (480, 640, 3) for d in detections)
        assert {x.name: x.state for x in c.sources()}["brick"] == "FINISHED"


def test_stream_cancel_from_another_thread(client):
    import threading
    stream = client.stream("carton_s", "carton_s")
    seen = []
    for detection in stream:
        seen.append(detection)
        if len(seen) == 1:
            threading.Timer(0.5, stream.cancel).start()
    # The loop ended without an error: cancelled by us, not failed.
    assert seen and seen[0].source == "carton_s"


def test_errors_carry_the_status(client):
    with pytest.raises(cornerpose.CornerposeError) as e:
        client.detect(source="nope", box="carton_s")
    assert e.value.code == "NOT_FOUND"
    with pytest.raises(cornerpose.CornerposeError) as e:
        client.detect(source="broken", box="carton_s")
    assert e.value.code == "UNAVAILABLE" and e.value.details
    with pytest.raises(cornerpose.CornerposeError) as e:
        client.detect(source="one", box="no_such_model")
    assert e.value.code == "INVALID_ARGUMENT"
    with pytest.raises(cornerpose.CornerposeError) as e:
        client.detect(depth=np.zeros((10, 10), np.uint16), intrinsics=KINECT, box="carton_s")
    assert e.value.code == "INVALID_ARGUMENT"
    with pytest.raises(cornerpose.CornerposeError) as e:
        list(client.stream("nope", "carton_s"))
    assert e.value.code == "NOT_FOUND"
    # The server still serves after all of them.
    assert client.health() == "SERVING"


def test_deadline(client, heap):
    with pytest.raises(cornerpose.CornerposeError) as e:
        client.detect(heap.cloud, box="carton_s", timeout=0.001)
    assert e.value.code == "DEADLINE_EXCEEDED"


def test_bad_arguments_fail_before_sending(client, heap):
    with pytest.raises(ValueError, match="exactly one"):
        client.detect(box="carton_s")
    with pytest.raises(ValueError, match="exactly one"):
        client.detect(heap.cloud, source="one", box="carton_s")
    with pytest.raises(ValueError, match="intrinsics"):
        client.detect(depth=np.zeros((4, 4), np.uint16), box="carton_s")
    with pytest.raises(ValueError, match="box"):
        client.detect(source="one", box=(0.3, 0.0, 0.1))
    with pytest.raises(ValueError, match="shape"):
        client.detect(np.zeros((5, 2)), box="carton_s")


def test_unreachable_server_fails_within_the_deadline():
    # Port 1 on loopback: nothing listens there.
    with cornerpose.Client("127.0.0.1:1", timeout=3) as c:
        with pytest.raises(cornerpose.CornerposeError) as e:
            c.health()
        assert e.value.code in ("UNAVAILABLE", "DEADLINE_EXCEEDED")
        with pytest.raises(cornerpose.CornerposeError) as e:
            c.wait_for_ready(timeout=0.5)
        assert e.value.code == "UNAVAILABLE"
