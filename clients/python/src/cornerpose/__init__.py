"""Python client of the cornerpose perception service.

    from cornerpose import Client
    with Client("localhost:50051") as client:
        detection = client.detect(source="cell", box="carton_s")
        if detection.best is not None:
            print(detection.best.pose)        # camera_T_box, 4x4 numpy array

See clients/python/README.md.
"""

from cornerpose.client import Client, DetectionStream, channel_credentials
from cornerpose.errors import CornerposeError
from cornerpose.transforms import as_transform, euler_zyx_deg, pose_matrix, rotation_vector
from cornerpose.types import Box, Detection, Intrinsics, Segment, Source, Timings

__all__ = [
    "Box", "Client", "CornerposeError", "Detection", "DetectionStream", "Intrinsics", "Segment",
    "Source", "Timings", "as_transform", "channel_credentials", "euler_zyx_deg", "pose_matrix",
    "rotation_vector",
]
__version__ = "0.1.0"
