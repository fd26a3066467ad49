"""The one exception the client raises for a failed call, carrying the gRPC status."""

from __future__ import annotations

import grpc


class PrimlabelError(Exception):
    """A call that failed: the gRPC code and message of its last attempt, and how many attempts
    were made. DATA_LOSS means the server's answer did not cover every point exactly once."""

    def __init__(self, code: grpc.StatusCode, message: str, attempts: int = 1):
        self.code = code
        self.message = message
        self.attempts = attempts
        text = f"{code.name}: {message}"
        if attempts > 1:
            text += f" (after {attempts} attempts)"
        super().__init__(text)


class InvalidInput(PrimlabelError, ValueError):
    """An argument the client refuses before calling the server (INVALID_ARGUMENT); also a
    ValueError, so either kind of handler catches it."""

    def __init__(self, message: str):
        super().__init__(grpc.StatusCode.INVALID_ARGUMENT, message)


class ProtocolError(Exception):
    """An answer that breaks the protocol (chunks overlapping, missing or of the wrong size); the
    client turns it into PrimlabelError(DATA_LOSS)."""


class DomainWarning(UserWarning):
    """The server labeled the cloud with a model trained for another kind of cloud (sensor, image
    size, point spacing or noise): the labels look plausible and are unreliable. The message is
    the summary's domain_warning."""
