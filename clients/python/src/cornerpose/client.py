"""The cornerpose client: one channel to a perception server, typed calls over it."""

from __future__ import annotations

import pathlib
from typing import Iterator, List, Optional, Union

import grpc

from cornerpose import messages
from cornerpose._stubs import health_pb2, health_pb2_grpc
from cornerpose._stubs import perception_service_pb2 as ps
from cornerpose._stubs import perception_service_pb2_grpc as ps_grpc
from cornerpose.errors import CornerposeError, from_rpc_error
from cornerpose.types import BoxSize, Detection, Source

PathOrBytes = Union[str, pathlib.Path, bytes, None]

# The server's default message limit (64 MiB): a VGA cloud is 3.7 MB, above
# gRPC's 4 MiB default once framed.
DEFAULT_MAX_MESSAGE_BYTES = 64 * 1024 * 1024


def _read(value: PathOrBytes, what: str) -> Optional[bytes]:
    if value is None or isinstance(value, bytes):
        return value
    path = pathlib.Path(value)
    try:
        return path.read_bytes()
    except OSError as e:
        raise ValueError(f"{what}: cannot read {path}: {e.strerror}") from e


def channel_credentials(ca: PathOrBytes = None, cert: PathOrBytes = None,
                        key: PathOrBytes = None) -> grpc.ChannelCredentials:
    """TLS credentials: `ca` verifies the server (None = the system's roots); `cert` and
    `key` (PEM, both or neither) are this client's certificate for mutual TLS."""
    if (cert is None) != (key is None):
        raise ValueError("tls: give both cert and key, or neither")
    return grpc.ssl_channel_credentials(root_certificates=_read(ca, "tls ca"),
                                        private_key=_read(key, "tls key"),
                                        certificate_chain=_read(cert, "tls cert"))


class DetectionStream:
    """Detections of a source's new frames, in increasing frame_id order.

    Iterate over it; it ends when a source that plays once finishes, and
    raises CornerposeError when the stream fails. `cancel()` (or leaving a
    `with` block) ends it from any thread.
    """

    def __init__(self, call):
        self._call = call

    def __iter__(self) -> Iterator[Detection]:
        try:
            for response in self._call:
                yield messages.detection_from_message(response)
        except grpc.RpcError as e:
            if e.code() == grpc.StatusCode.CANCELLED and self._call.cancelled():
                return
            raise from_rpc_error("StreamDetections", e) from None

    def cancel(self) -> None:
        self._call.cancel()

    def __enter__(self) -> "DetectionStream":
        return self

    def __exit__(self, *exc) -> None:
        self.cancel()


class Client:
    """A connection to a cornerpose perception server.

    target: "host:port" (any gRPC target, "dns:///svc:50051" included).
    Plaintext unless `tls=True` or any of ca, cert, key is given; `ca`, `cert`,
    `key` are PEM file paths or bytes (see channel_credentials);
    `server_name` overrides the name the server's certificate is checked
    against. `timeout` is the default deadline of unary calls, seconds
    (None = none); every call takes its own `timeout` too.
    """

    def __init__(self, target: str = "localhost:50051", *, tls: bool = False,
                 ca: PathOrBytes = None, cert: PathOrBytes = None, key: PathOrBytes = None,
                 server_name: Optional[str] = None, timeout: Optional[float] = 10.0,
                 max_message_bytes: int = DEFAULT_MAX_MESSAGE_BYTES):
        if timeout is not None and not timeout > 0:
            raise ValueError(f"timeout must be > 0 seconds or None; got {timeout!r}")
        if max_message_bytes <= 0:
            raise ValueError(f"max_message_bytes must be > 0; got {max_message_bytes}")
        options = [("grpc.max_receive_message_length", max_message_bytes),
                   ("grpc.max_send_message_length", max_message_bytes)]
        if server_name:
            options.append(("grpc.ssl_target_name_override", server_name))
        if tls or ca is not None or cert is not None or key is not None:
            self._channel = grpc.secure_channel(target, channel_credentials(ca, cert, key),
                                                options=options)
        else:
            self._channel = grpc.insecure_channel(target, options=options)
        self.target = target
        self.timeout = timeout
        self._stub = ps_grpc.PerceptionServiceStub(self._channel)
        self._health = health_pb2_grpc.HealthStub(self._channel)

    # -- calls -------------------------------------------------------------

    def detect(self, cloud=None, *, depth=None, intrinsics=None, source: Optional[str] = None,
               box: BoxSize, edge_radius_m: Optional[float] = None,
               edge_threshold: Optional[float] = None, ransac_threshold_m: Optional[float] = None,
               include_edge_points: bool = False, include_cloud: bool = False,
               timeout: Optional[float] = -1) -> Detection:
        """Runs the detector once, on exactly one of:

        - `cloud`: an (N, 3) unorganized or (H, W, 3) organized array, camera
          frame, metres, NaN = no return (`intrinsics` optional: the camera of
          an unorganized cloud);
        - `depth` (H, W) uint16 millimetres or float metres, with `intrinsics`
          (Intrinsics, "w,h,fx,fy,cx,cy", 6 numbers or an intrinsics.txt Path);
        - `source`: the newest frame of a server-side source (with
          `include_cloud` the frame's cloud comes back too).

        box: (l, b, h) metres or a model name. The overrides change the
        detector's parameters for this call only. Raises ValueError for bad
        arguments, CornerposeError for an error status.
        """
        given = [name for name, v in (("cloud", cloud), ("depth", depth), ("source", source))
                 if v is not None]
        if len(given) != 1:
            raise ValueError(f"detect needs exactly one of cloud, depth, source; got {given or 'none'}")
        request = ps.DetectRequest(include_edge_points=include_edge_points,
                                   include_cloud=include_cloud)
        if cloud is not None:
            request.cloud.CopyFrom(messages.cloud_message(cloud))
        elif depth is not None:
            if intrinsics is None:
                raise ValueError("detect: a depth image needs intrinsics")
            request.depth_image.CopyFrom(messages.depth_message(depth))
        else:
            if not source:
                raise ValueError("detect: source name is empty")
            request.source = source
        if intrinsics is not None:
            request.intrinsics.CopyFrom(messages.intrinsics_message(intrinsics))
        messages.set_box(request, box)
        messages.set_overrides(request, edge_radius_m, edge_threshold, ransac_threshold_m)
        response = self._unary("Detect", self._stub.Detect, request, timeout)
        return messages.detection_from_message(response)

    def stream(self, source: str, box: BoxSize, *, edge_radius_m: Optional[float] = None,
               edge_threshold: Optional[float] = None, ransac_threshold_m: Optional[float] = None,
               include_edge_points: bool = False, include_cloud: bool = False,
               timeout: Optional[float] = None) -> DetectionStream:
        """Detections on each new frame of `source`, as an iterator (see DetectionStream).

        `timeout` bounds the whole stream, seconds (default none: until the
        source ends or the stream is cancelled).
        """
        if not source:
            raise ValueError("stream: source name is empty")
        request = ps.StreamDetectionsRequest(source=source, include_edge_points=include_edge_points,
                                             include_cloud=include_cloud)
        messages.set_box(request, box)
        messages.set_overrides(request, edge_radius_m, edge_threshold, ransac_threshold_m)
        return DetectionStream(self._stub.StreamDetections(request, timeout=timeout))

    def sources(self, *, timeout: Optional[float] = -1) -> List[Source]:
        """The server's frame sources and their states."""
        response = self._unary("ListSources", self._stub.ListSources, ps.ListSourcesRequest(),
                               timeout)
        return [messages.source_from_message(s) for s in response.sources]

    def health(self, service: str = "", *, timeout: Optional[float] = -1) -> str:
        """The server's gRPC health status: "SERVING", "NOT_SERVING", "SERVICE_UNKNOWN" or
        "UNKNOWN" ("" = the whole server, or one service by its full name)."""
        try:
            response = self._unary("Health.Check", self._health.Check,
                                   health_pb2.HealthCheckRequest(service=service), timeout)
        except CornerposeError as e:
            # The health protocol answers NOT_FOUND for a service it does not know.
            if e.code == "NOT_FOUND":
                return "SERVICE_UNKNOWN"
            raise
        return health_pb2.HealthCheckResponse.ServingStatus.Name(response.status)

    def wait_for_ready(self, timeout: float = 10.0) -> None:
        """Blocks until the channel is connected; CornerposeError(UNAVAILABLE) after `timeout`."""
        try:
            grpc.channel_ready_future(self._channel).result(timeout=timeout)
        except grpc.FutureTimeoutError:
            raise CornerposeError("connect", grpc.StatusCode.UNAVAILABLE,
                                  f"no connection to {self.target} within {timeout} s") from None

    # -- plumbing ----------------------------------------------------------

    def _unary(self, method: str, call, request, timeout):
        # -1 = the client's default deadline; None = no deadline.
        deadline = self.timeout if timeout == -1 else timeout
        try:
            return call(request, timeout=deadline)
        except grpc.RpcError as e:
            raise from_rpc_error(method, e) from None

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
