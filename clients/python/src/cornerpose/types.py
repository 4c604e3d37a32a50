"""What the client returns: plain dataclasses with numpy arrays, no protobuf.

Frames and units as in the API (proto/cornerpose/v1): the camera frame is
x right, y down, z forward; metres; the box frame has its origin at the box
centroid, x along l, y along b, z along h.
"""

from __future__ import annotations

import dataclasses
import pathlib
from typing import List, Optional, Sequence, Tuple, Union

import numpy as np


@dataclasses.dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics of a depth camera, pixels."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def parse(cls, value: Union["Intrinsics", str, Sequence[float], pathlib.Path]) -> "Intrinsics":
        """From an Intrinsics, "w,h,fx,fy,cx,cy", a 6-sequence, or an intrinsics.txt path.

        Raises ValueError naming the value when it is none of these or a
        size or focal length is not positive.
        """
        if isinstance(value, Intrinsics):
            return value
        if isinstance(value, pathlib.Path):
            value = value.read_text()
        if isinstance(value, str):
            parts = [p.strip() for p in value.strip().split(",")]
        else:
            parts = list(value)
        if len(parts) != 6:
            raise ValueError(f"intrinsics are width,height,fx,fy,cx,cy; got {value!r}")
        try:
            w, h = (int(float(p)) for p in parts[:2])
            fx, fy, cx, cy = (float(p) for p in parts[2:])
        except (TypeError, ValueError) as e:
            raise ValueError(f"intrinsics are width,height,fx,fy,cx,cy; got {value!r}") from e
        if w <= 0 or h <= 0 or not fx > 0 or not fy > 0:
            raise ValueError(f"intrinsics need width, height, fx, fy > 0; got {value!r}")
        return cls(w, h, fx, fy, cx, cy)

    def depth_to_cloud(self, depth: np.ndarray) -> np.ndarray:
        """An organized (H, W, 3) float32 cloud from a depth image (uint16 mm or float m).

        No return (0 or NaN) becomes NaN, as the service expects.
        """
        d = np.asarray(depth)
        if d.shape != (self.height, self.width):
            raise ValueError(f"depth image is {d.shape}, intrinsics say ({self.height}, {self.width})")
        z = d.astype(np.float64) / 1000.0 if d.dtype == np.uint16 else d.astype(np.float64)
        z[~(z > 0)] = np.nan
        v, u = np.mgrid[0 : self.height, 0 : self.width]
        x = (u - self.cx) / self.fx * z
        y = (v - self.cy) / self.fy * z
        return np.stack([x, y, z], axis=-1).astype(np.float32)


# Grasp faces as the offline tool writes them (BoxFace in the API).
FACE_NAMES = {1: "+x", 2: "-x", 3: "+y", 4: "-y", 5: "+z", 6: "-z"}


@dataclasses.dataclass
class Box:
    """A box the detector confirmed."""

    # camera_T_box, 4x4: maps box coordinates into the camera frame.
    pose: np.ndarray
    # Confidence in [0, 1].
    score: float
    # The face looking at the camera ("+z" is the face at z = +h/2), where a
    # suction gripper should grasp; its centre and outward unit normal in the
    # camera frame.
    grasp_face: str
    grasp_centre: np.ndarray
    grasp_normal: np.ndarray

    @property
    def position(self) -> np.ndarray:
        """The box centroid in the camera frame, metres."""
        return self.pose[:3, 3]

    def in_frame(self, parent_T_camera: np.ndarray) -> "Box":
        """This box expressed in another frame (e.g. a robot base frame, given the hand-eye
        calibration base_T_camera as a 4x4 transform)."""
        t = np.asarray(parent_T_camera, dtype=float)
        return Box(pose=t @ self.pose, score=self.score, grasp_face=self.grasp_face,
                   grasp_centre=t[:3, :3] @ self.grasp_centre + t[:3, 3],
                   grasp_normal=t[:3, :3] @ self.grasp_normal)


@dataclasses.dataclass
class Segment:
    """A straight edge: its two extremities (camera frame, metres) and its point count."""

    end1: np.ndarray
    end2: np.ndarray
    num_points: int

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end2 - self.end1))


@dataclasses.dataclass
class Timings:
    """Wall-clock time of each detector stage, milliseconds."""

    preprocess_ms: float = 0.0
    edge_points_ms: float = 0.0
    edge_segments_ms: float = 0.0
    clubbing_ms: float = 0.0
    poses_ms: float = 0.0
    total_ms: float = 0.0


@dataclasses.dataclass
class Detection:
    """One detection: boxes best score first, the edges and corners they came from."""

    boxes: List[Box]
    segments: List[Segment]
    # (K, 3) corner positions, camera frame, metres.
    corners: np.ndarray
    # (M, 3) edge points; empty unless include_edge_points.
    edge_points: np.ndarray
    timings: Timings
    # Set when the detection ran on a server-side source: the source, the
    # frame's id (increasing per source) and capture time (ns since the epoch).
    source: str = ""
    frame_id: int = 0
    capture_time_unix_nanos: int = 0
    # The frame's cloud when include_cloud was asked: (H, W, 3) float32 when
    # organized, (N, 3) otherwise; NaN = no return.
    cloud: Optional[np.ndarray] = None

    @property
    def best(self) -> Optional[Box]:
        """The highest-scoring box, or None when none was found."""
        return self.boxes[0] if self.boxes else None


@dataclasses.dataclass(frozen=True)
class Source:
    """A frame source the server grabs from."""

    name: str
    description: str
    # STARTING, RUNNING, FAILED or FINISHED.
    state: str
    # Why it is in that state (the error when FAILED); may be empty.
    state_reason: str


# A box size: (l, b, h) in metres, or a model name the server knows
# (brick, carton_s, carton_l, carton_sq, carton_flat, or one from its config).
BoxSize = Union[str, Tuple[float, float, float], Sequence[float]]
