"""Conversion between numpy / the client's dataclasses and the API's protobuf messages.

Every check here gives a ValueError that names the argument and what was
wrong with it, before anything is sent; the server checks again.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from cornerpose._stubs import geometry_pb2 as geo
from cornerpose._stubs import perception_service_pb2 as ps
from cornerpose.transforms import pose_matrix
from cornerpose.types import (FACE_NAMES, Box, BoxSize, Detection, Intrinsics, Segment, Source,
                              Timings)


def cloud_message(cloud) -> geo.PointCloud:
    """A PointCloud from an (N, 3) unorganized or (H, W, 3) organized array, metres."""
    a = np.asarray(cloud)
    if a.ndim not in (2, 3) or a.shape[-1] != 3:
        raise ValueError(f"cloud must be (N, 3) or (H, W, 3); got shape {a.shape}")
    if not np.issubdtype(a.dtype, np.floating) and not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"cloud must hold numbers; got dtype {a.dtype}")
    height, width = (1, a.shape[0]) if a.ndim == 2 else a.shape[:2]
    data = np.ascontiguousarray(a, dtype="<f4").tobytes()
    return geo.PointCloud(xyz=data, width=width, height=height)


def depth_message(depth) -> geo.DepthImage:
    """A DepthImage from an (H, W) array: uint16 = millimetres, floating = metres."""
    a = np.asarray(depth)
    if a.ndim != 2:
        raise ValueError(f"depth must be an (H, W) image; got shape {a.shape}")
    if a.dtype == np.uint16:
        return geo.DepthImage(data=np.ascontiguousarray(a, dtype="<u2").tobytes(), width=a.shape[1],
                              height=a.shape[0], encoding=geo.DEPTH_ENCODING_UINT16_MM)
    if np.issubdtype(a.dtype, np.floating):
        return geo.DepthImage(data=np.ascontiguousarray(a, dtype="<f4").tobytes(), width=a.shape[1],
                              height=a.shape[0], encoding=geo.DEPTH_ENCODING_FLOAT32_M)
    raise ValueError(f"depth must be uint16 millimetres or float metres; got dtype {a.dtype}")


def intrinsics_message(value) -> geo.CameraIntrinsics:
    k = Intrinsics.parse(value)
    return geo.CameraIntrinsics(width=k.width, height=k.height, fx=k.fx, fy=k.fy, cx=k.cx, cy=k.cy)


def set_box(request, box: BoxSize) -> None:
    """Sets request.box (l, b, h) or request.box_model (a name)."""
    if isinstance(box, str):
        if not box:
            raise ValueError("box model name is empty")
        request.box_model = box
        return
    try:
        dims = [float(v) for v in box]
    except TypeError as e:
        raise ValueError(f"box is (l, b, h) in metres or a model name; got {box!r}") from e
    if len(dims) != 3 or not all(np.isfinite(d) and d > 0 for d in dims):
        raise ValueError(f"box is (l, b, h) in metres, each > 0; got {box!r}")
    request.box.CopyFrom(geo.BoxDimensions(l=dims[0], b=dims[1], h=dims[2]))


def set_overrides(request, edge_radius_m: Optional[float], edge_threshold: Optional[float],
                  ransac_threshold_m: Optional[float]) -> None:
    if edge_radius_m is not None:
        request.overrides.edge_radius_m = float(edge_radius_m)
    if edge_threshold is not None:
        request.overrides.edge_threshold = float(edge_threshold)
    if ransac_threshold_m is not None:
        request.overrides.ransac_threshold_m = float(ransac_threshold_m)


def _vec(v) -> np.ndarray:
    return np.array([v.x, v.y, v.z])


def _points(vectors) -> np.ndarray:
    return np.array([[v.x, v.y, v.z] for v in vectors], dtype=float).reshape(-1, 3)


def cloud_array(cloud: geo.PointCloud) -> Optional[np.ndarray]:
    """(H, W, 3) float32 for an organized cloud, (N, 3) otherwise; None when empty."""
    if not cloud.xyz:
        return None
    points = np.frombuffer(cloud.xyz, dtype="<f4").reshape(-1, 3)
    if cloud.height > 1:
        return points.reshape(cloud.height, cloud.width, 3)
    return points


def box_from_message(b) -> Box:
    p, q = b.camera_pose_box.position, b.camera_pose_box.orientation
    return Box(pose=pose_matrix((p.x, p.y, p.z), (q.w, q.x, q.y, q.z)), score=b.score,
               grasp_face=FACE_NAMES.get(b.grasp_face, "?"), grasp_centre=_vec(b.grasp_centre),
               grasp_normal=_vec(b.grasp_normal))


def detection_from_message(r: ps.DetectResponse) -> Detection:
    t = r.timings
    return Detection(
        boxes=[box_from_message(b) for b in r.boxes],
        segments=[Segment(_vec(s.end1), _vec(s.end2), s.num_points) for s in r.segments],
        corners=_points(c.position for c in r.corners),
        edge_points=_points(r.edge_points),
        timings=Timings(t.preprocess_ms, t.edge_points_ms, t.edge_segments_ms, t.clubbing_ms,
                        t.poses_ms, t.total_ms),
        source=r.source, frame_id=r.frame_id, capture_time_unix_nanos=r.capture_time_unix_nanos,
        cloud=cloud_array(r.cloud) if r.HasField("cloud") else None)


def source_from_message(s) -> Source:
    state = ps.SourceState.Name(s.state).removeprefix("SOURCE_STATE_")
    return Source(name=s.name, description=s.description, state=state,
                  state_reason=s.state_reason)
