"""The one exception the client raises for a failed call."""

from __future__ import annotations

import grpc


class CornerposeError(Exception):
    """A call the server (or the channel) answered with an error status.

    `code` is the gRPC status name ("NOT_FOUND", "INVALID_ARGUMENT",
    "UNAVAILABLE", "DEADLINE_EXCEEDED", ...), `details` the server's message.
    Bad arguments caught before sending are ValueError instead.
    """

    def __init__(self, method: str, code: grpc.StatusCode, details: str):
        self.method = method
        self.status_code = code
        self.code = code.name
        self.details = details
        super().__init__(f"{method}: {code.name}: {details}")


def from_rpc_error(method: str, error: grpc.RpcError) -> CornerposeError:
    code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
    details = error.details() if hasattr(error, "details") else str(error)
    return CornerposeError(method, code, details or "")
