"""The generated protobuf and gRPC modules, with a clear error when they are missing.

They are generated when the package is built (setup.py), so a source checkout
on sys.path without an install has none.
"""

try:
    from cornerpose._health import health_pb2, health_pb2_grpc
    from cornerpose.v1 import (
        geometry_pb2,
        perception_service_pb2,
        perception_service_pb2_grpc,
        robot_client_config_pb2,
        robot_client_service_pb2,
        robot_client_service_pb2_grpc,
    )
except ImportError as e:  # pragma: no cover - depends on how it was installed
    raise ImportError(
        "cornerpose: the generated gRPC modules are missing; install the package "
        "(pip install clients/python) instead of importing it from the source tree") from e

__all__ = [
    "geometry_pb2", "health_pb2", "health_pb2_grpc", "perception_service_pb2",
    "perception_service_pb2_grpc", "robot_client_config_pb2", "robot_client_service_pb2",
    "robot_client_service_pb2_grpc",
]
