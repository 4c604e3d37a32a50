"""Rigid transforms as numpy 4x4 matrices (metres), and unit quaternions (w, x, y, z)."""

from __future__ import annotations

from typing import Sequence

import numpy as np


def quaternion_to_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """Rotation matrix (3x3) of a quaternion (Hamilton, w x y z); normalized first.

    Raises ValueError for a zero or non-finite quaternion.
    """
    q = np.array([w, x, y, z], dtype=float)
    n = np.linalg.norm(q)
    if not np.isfinite(n) or n < 1e-12:
        raise ValueError(f"quaternion ({w}, {x}, {y}, {z}) is not a rotation")
    w, x, y, z = q / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def matrix_to_quaternion(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a 3x3 rotation matrix (Shepperd's method)."""
    m = np.asarray(rotation, dtype=float)[:3, :3]
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s]
    q = np.array(q)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def pose_matrix(position: Sequence[float], quaternion: Sequence[float]) -> np.ndarray:
    """4x4 transform from a position (x, y, z) and a quaternion (w, x, y, z)."""
    t = np.eye(4)
    t[:3, :3] = quaternion_to_matrix(*quaternion)
    t[:3, 3] = np.asarray(position, dtype=float)
    return t


def rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Axis times angle (radians) of a 3x3 rotation: the UR controller's pose rotation."""
    w, x, y, z = matrix_to_quaternion(rotation)
    sin_half = np.linalg.norm([x, y, z])
    if sin_half < 1e-12:
        return np.zeros(3)
    angle = 2.0 * np.arctan2(sin_half, w)
    return np.array([x, y, z]) / sin_half * angle


def euler_zyx_deg(rotation: np.ndarray) -> np.ndarray:
    """Yaw, pitch, roll (z, y', x'' intrinsic), degrees, as `cornerpose detect` prints them."""
    m = np.asarray(rotation, dtype=float)
    yaw = np.arctan2(m[1, 0], m[0, 0])
    pitch = np.arcsin(np.clip(-m[2, 0], -1.0, 1.0))
    roll = np.arctan2(m[2, 1], m[2, 2])
    return np.degrees([yaw, pitch, roll])


def as_transform(value) -> np.ndarray:
    """A 4x4 transform from a 4x4 (or 3x4) array, or (x, y, z, qw, qx, qy, qz).

    Raises ValueError naming what it got when it is neither, or when the
    rotation part is not a rotation.
    """
    a = np.asarray(value, dtype=float)
    if a.shape == (7,):
        return pose_matrix(a[:3], a[3:])
    if a.shape in ((4, 4), (3, 4)):
        t = np.eye(4)
        t[: a.shape[0]] = a
        r = t[:3, :3]
        if not np.allclose(r @ r.T, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
            raise ValueError("transform's rotation part is not a rotation matrix")
        if a.shape == (4, 4) and not np.allclose(a[3], [0, 0, 0, 1]):
            raise ValueError(f"transform's last row is {a[3].tolist()}, not [0, 0, 0, 1]")
        return t
    raise ValueError(f"a transform is 4x4, 3x4 or (x, y, z, qw, qx, qy, qz); got shape {a.shape}")
