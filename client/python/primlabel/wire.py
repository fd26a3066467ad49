"""The packed arrays of the labeling API (proto/include/primlabel/wire/packing.hpp): float32 xyz,
normals, descriptors and probabilities and uint32 labels, little-endian and point-major; and the
reassembly of an answer's LabelChunks in input order (as client/src/label_assembler.cpp)."""

from __future__ import annotations

import numpy as np

from .errors import InvalidInput, ProtocolError

FLOAT32_LE = np.dtype("<f4")
UINT32_LE = np.dtype("<u4")
NO_SEGMENT = 0xFFFFFFFF  # LabelChunk.segments: the point is in no fitted segment
NO_OBJECT = 0xFFFFFFFF  # LabelChunk.objects: neither the table (0) nor an object (k >= 1)


def as_points(values, what: str, points: int | None = None) -> np.ndarray:
    """`values` as a C-contiguous little-endian float32 (N, 3) array, the wire layout. Values
    beyond float32's range become +-inf, which the server treats as non-finite."""
    array = np.asarray(values)
    if array.dtype.kind not in "fiu":
        raise InvalidInput(f"{what} must be real numbers, got dtype {array.dtype}")
    if array.ndim != 2 or array.shape[1] != 3:
        raise InvalidInput(f"{what} must have shape (N, 3), got {array.shape}")
    if points is not None and array.shape[0] != points:
        raise InvalidInput(f"{what} has {array.shape[0]} rows for {points} points")
    with np.errstate(over="ignore", invalid="ignore"):
        return np.ascontiguousarray(array, dtype=FLOAT32_LE)


def _columns(size: int, count: int, what: str, first: int) -> int:
    """Values per point of an optional array in a chunk of `count` points; -1 when absent."""
    if size == 0:
        return -1
    if count == 0 or size % (4 * count) != 0:
        raise ProtocolError(
            f"chunk at point {first}: {size} bytes of {what} do not divide into {count} points"
        )
    return size // (4 * count)


class LabelAssembler:
    """Puts the chunks of one answer back together and checks they cover every point exactly
    once with consistent column counts; any violation is a ProtocolError, never patched over."""

    def __init__(self, points: int, want_descriptors: bool, want_probabilities: bool,
                 want_segments: bool = False, want_objects: bool = False):
        self._points = points
        self._want_descriptors = want_descriptors
        self._want_probabilities = want_probabilities
        self._want_segments = want_segments
        self._want_objects = want_objects
        self._covered = np.zeros(points, dtype=bool)
        self._covered_count = 0
        self.labels = np.zeros(points, dtype=np.uint32)
        self.descriptors: np.ndarray | None = None
        self.probabilities: np.ndarray | None = None
        self.segments: np.ndarray | None = None
        self.objects: np.ndarray | None = None

    def add(self, chunk) -> None:
        first, count = chunk.first_point, chunk.point_count
        at = f"chunk at point {first}"
        if first > self._points or count > self._points - first:
            raise ProtocolError(f"{at}: {count} points run past the {self._points} points sent")
        if len(chunk.labels) != 4 * count:
            raise ProtocolError(f"{at}: {len(chunk.labels)} bytes of labels for {count} points")
        end = first + count
        seen = self._covered[first:end]
        if seen.any():
            raise ProtocolError(f"{at}: point {first + int(np.argmax(seen))} twice")

        dim = _columns(len(chunk.descriptors), count, "descriptors", first)
        if self._want_descriptors and count > 0 and dim < 0:
            raise ProtocolError(f"{at}: descriptors were asked for but are missing")
        if dim > 0:
            self.descriptors = self._place(self.descriptors, chunk.descriptors, dim, first, end,
                                           np.nan, "descriptor values", at)

        classes = _columns(len(chunk.probabilities), count, "probabilities", first)
        if self._want_probabilities and count > 0 and classes < 0:
            raise ProtocolError(f"{at}: probabilities were asked for but are missing")
        if classes > 0:
            self.probabilities = self._place(self.probabilities, chunk.probabilities, classes,
                                             first, end, 0.0, "probabilities", at)

        self.segments = self._place_ids(self.segments, chunk.segments, self._want_segments,
                                        "segment ids", first, end, at)
        self.objects = self._place_ids(self.objects, chunk.objects, self._want_objects,
                                       "object ids", first, end, at)

        self.labels[first:end] = np.frombuffer(chunk.labels, dtype=UINT32_LE)
        self._covered[first:end] = True
        self._covered_count += count

    def _place_ids(self, target, payload, wanted, what, first, end, at):
        """One uint32 a point (segment or object ids), all 0xFFFFFFFF until a chunk fills it."""
        count = end - first
        columns = _columns(len(payload), count, what, first)
        if wanted and count > 0 and columns < 0:
            raise ProtocolError(f"{at}: {what} were asked for but are missing")
        if columns > 1:
            raise ProtocolError(f"{at}: {columns} {what} a point, not 1")
        if columns == 1:
            if target is None:
                target = np.full(self._points, 0xFFFFFFFF, dtype=np.uint32)
            target[first:end] = np.frombuffer(payload, dtype=UINT32_LE)
        return target

    def _place(self, target, payload, columns, first, end, fill, what, at):
        if target is None:
            target = np.full((self._points, columns), fill, dtype=np.float32)
        elif target.shape[1] != columns:
            raise ProtocolError(
                f"{at}: {columns} {what} a point, earlier chunks had {target.shape[1]}"
            )
        target[first:end] = np.frombuffer(payload, dtype=FLOAT32_LE).reshape(end - first, columns)
        return target

    def finish(self, summary):
        """Checks coverage, column counts and segment ids against the summary; returns
        (labels, descriptors, probabilities, classes as (id, name) pairs, segments, objects)."""
        if self._covered_count != self._points:
            missing = int(np.argmin(self._covered))
            raise ProtocolError(
                f"the answer covers {self._covered_count} of {self._points} points; "
                f"first missing point {missing}"
            )
        if summary.points_received != self._points:
            raise ProtocolError(
                f"the server received {summary.points_received} points of {self._points} sent"
            )
        classes = [(c.id, c.name) for c in summary.classes]
        descriptors, probabilities = self.descriptors, self.probabilities
        if descriptors is not None:
            if summary.descriptor_dim not in (0, descriptors.shape[1]):
                raise ProtocolError(
                    f"the summary says {summary.descriptor_dim} descriptor values a point, "
                    f"the chunks carried {descriptors.shape[1]}"
                )
        elif self._want_descriptors:  # no points: an empty array of the right width
            descriptors = np.zeros((0, summary.descriptor_dim), dtype=np.float32)
        if probabilities is not None:
            if probabilities.shape[1] != len(classes):
                raise ProtocolError(
                    f"the summary lists {len(classes)} classes, the chunks carried "
                    f"{probabilities.shape[1]} probabilities a point"
                )
        elif self._want_probabilities:
            probabilities = np.zeros((0, len(classes)), dtype=np.float32)
        segments = self.segments
        if segments is not None:
            named = segments[segments != NO_SEGMENT]
            if named.size and int(named.max()) >= len(summary.primitives):
                point = int(np.argmax((segments != NO_SEGMENT)
                                      & (segments >= len(summary.primitives))))
                raise ProtocolError(
                    f"point {point} is in segment {int(segments[point])}, the summary has "
                    f"{len(summary.primitives)} primitives"
                )
        elif self._want_segments:
            segments = np.zeros(0, dtype=np.uint32)
        objects = self.objects
        if objects is not None:
            named = objects[objects != NO_OBJECT]
            bad = (named > len(summary.objects)) | ((named == 0) & (not summary.HasField("table")))
            if bad.any():
                value = int(named[np.argmax(bad)])
                raise ProtocolError(
                    f"a point is in object {value}, the summary has {len(summary.objects)} "
                    f"objects{'' if summary.HasField('table') else ' and no table'}"
                )
        elif self._want_objects:
            objects = np.zeros(0, dtype=np.uint32)
        return self.labels, descriptors, probabilities, classes, segments, objects


# grpc.health.v1 by hand (as client/src/health_wire.cpp): two one-field messages do not justify a
# dependency on grpcio-health-checking, which Debian does not package.


def _put_varint(out: bytearray, value: int) -> None:
    while value >= 0x80:
        out.append((value & 0x7F) | 0x80)
        value >>= 7
    out.append(value)


def _get_varint(data: bytes, pos: int) -> tuple[int, int]:
    value = 0
    for shift in range(0, 64, 7):
        if pos >= len(data):
            break
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, pos
    raise ProtocolError("malformed grpc.health.v1 response")


def encode_health_request(service: str) -> bytes:
    out = bytearray()
    if service:  # proto3 omits the default
        encoded = service.encode()
        out.append(0x0A)  # field 1, length-delimited
        _put_varint(out, len(encoded))
        out += encoded
    return bytes(out)


def decode_health_status(data: bytes) -> int:
    status, pos = 0, 0  # absent = UNKNOWN
    while pos < len(data):
        key, pos = _get_varint(data, pos)
        wire_type = key & 7
        if wire_type == 0:
            value, pos = _get_varint(data, pos)
            if key >> 3 == 1:
                status = value
        elif wire_type in (1, 5):
            pos += 8 if wire_type == 1 else 4
        elif wire_type == 2:
            length, pos = _get_varint(data, pos)
            pos += length
        else:
            raise ProtocolError("malformed grpc.health.v1 response")
        if pos > len(data):
            raise ProtocolError("malformed grpc.health.v1 response")
    return status
