"""The client's own arithmetic: quaternions, transforms, intrinsics, argument checks."""

import numpy as np
import pytest

import cornerpose
from cornerpose import messages, transforms


def random_quaternions(n, seed=1):
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_quaternion_matrix_round_trip():
    for q in random_quaternions(200):
        r = transforms.quaternion_to_matrix(*q)
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)
        back = transforms.matrix_to_quaternion(r)
        # q and -q are the same rotation.
        assert min(np.abs(back - q).max(), np.abs(back + q).max()) < 1e-9


def test_quaternion_to_matrix_known_rotations():
    # 90 degrees about z maps x to y.
    c = np.sqrt(0.5)
    np.testing.assert_allclose(transforms.quaternion_to_matrix(c, 0, 0, c) @ [1, 0, 0], [0, 1, 0],
                               atol=1e-12)
    # 180 degrees about x (the demo camera looking down): y -> -y, z -> -z.
    np.testing.assert_allclose(transforms.quaternion_to_matrix(0, 1, 0, 0), np.diag([1, -1, -1]),
                               atol=1e-12)
    with pytest.raises(ValueError, match="not a rotation"):
        transforms.quaternion_to_matrix(0, 0, 0, 0)


def test_rotation_vector_near_zero_and_pi():
    assert np.allclose(transforms.rotation_vector(np.eye(3)), 0)
    # 180 degrees about x: axis x, angle pi.
    np.testing.assert_allclose(transforms.rotation_vector(np.diag([1.0, -1, -1])), [np.pi, 0, 0],
                               atol=1e-9)
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    for angle in (1e-4, 0.3, 2.0, np.pi - 1e-4):
        q = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
        rv = transforms.rotation_vector(transforms.quaternion_to_matrix(*q))
        np.testing.assert_allclose(rv, axis * angle, atol=1e-7)


def test_as_transform_accepts_and_rejects():
    t = transforms.as_transform([0.1, 0.2, 0.3, 0, 1, 0, 0])
    np.testing.assert_allclose(t[:3, 3], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(t[:3, :3], np.diag([1, -1, -1]), atol=1e-12)
    np.testing.assert_allclose(transforms.as_transform(t), t)
    with pytest.raises(ValueError, match="shape"):
        transforms.as_transform([1, 2, 3])
    with pytest.raises(ValueError, match="not a rotation"):
        transforms.as_transform(np.diag([2.0, 1, 1, 1]))
    bad = np.eye(4)
    bad[3, 0] = 1
    with pytest.raises(ValueError, match="last row"):
        transforms.as_transform(bad)


def test_box_in_frame_moves_pose_and_grasp():
    box = cornerpose.Box(pose=transforms.pose_matrix([0, 0, 1], [1, 0, 0, 0]), score=0.9,
                         grasp_face="+z", grasp_centre=np.array([0, 0, 0.9]),
                         grasp_normal=np.array([0, 0, -1.0]))
    base_T_camera = transforms.as_transform([0.0, -0.5, 1.3, 0, 1, 0, 0])
    moved = box.in_frame(base_T_camera)
    np.testing.assert_allclose(moved.position, [0, -0.5, 0.3], atol=1e-12)
    np.testing.assert_allclose(moved.grasp_centre, [0, -0.5, 0.4], atol=1e-12)
    np.testing.assert_allclose(moved.grasp_normal, [0, 0, 1], atol=1e-12)


def test_intrinsics_parse(tmp_path):
    k = cornerpose.Intrinsics.parse("640,480,525,525,319.5,239.5")
    assert (k.width, k.height, k.fx, k.cy) == (640, 480, 525.0, 239.5)
    assert cornerpose.Intrinsics.parse([640, 480, 525, 525, 319.5, 239.5]) == k
    path = tmp_path / "intrinsics.txt"
    path.write_text("640,480,525,525,319.5,239.5\n")
    import pathlib
    assert cornerpose.Intrinsics.parse(pathlib.Path(path)) == k
    for bad in ("640,480,525", "a,b,c,d,e,f", "0,480,525,525,1,1", "640,480,-1,525,1,1"):
        with pytest.raises(ValueError, match="intrinsics"):
            cornerpose.Intrinsics.parse(bad)


def test_depth_to_cloud_back_projects():
    k = cornerpose.Intrinsics(4, 3, 2.0, 2.0, 1.5, 1.0)
    depth = np.full((3, 4), 1000, dtype=np.uint16)
    depth[0, 0] = 0
    cloud = k.depth_to_cloud(depth)
    assert cloud.shape == (3, 4, 3) and cloud.dtype == np.float32
    assert np.isnan(cloud[0, 0]).all()
    np.testing.assert_allclose(cloud[2, 3], [(3 - 1.5) / 2, (2 - 1.0) / 2, 1.0])
    with pytest.raises(ValueError, match="intrinsics say"):
        k.depth_to_cloud(np.zeros((4, 4), dtype=np.uint16))


def test_messages_reject_bad_arguments():
    with pytest.raises(ValueError, match="shape"):
        messages.cloud_message(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="shape"):
        messages.depth_message(np.zeros((2, 2, 2), dtype=np.uint16))
    with pytest.raises(ValueError, match="dtype"):
        messages.depth_message(np.zeros((2, 2), dtype=np.int32))
    request = messages.ps.DetectRequest()
    for bad in ((0.3, 0.2), (0.3, -0.2, 0.1), (0.3, float("nan"), 0.1), "", 5):
        with pytest.raises(ValueError, match="box"):
            messages.set_box(request, bad)


def test_cloud_message_layout():
    organized = np.arange(2 * 3 * 3, dtype=np.float64).reshape(2, 3, 3)
    m = messages.cloud_message(organized)
    assert (m.width, m.height, len(m.xyz)) == (3, 2, 2 * 3 * 12)
    # Row-major: point (u, v) at index v * width + u, float32 little-endian.
    np.testing.assert_array_equal(np.frombuffer(m.xyz, "<f4").reshape(2, 3, 3), organized)
    np.testing.assert_array_equal(messages.cloud_array(m), organized)
    flat = messages.cloud_message(organized.reshape(-1, 3))
    assert (flat.width, flat.height) == (6, 1)
    assert messages.cloud_array(flat).shape == (6, 3)
