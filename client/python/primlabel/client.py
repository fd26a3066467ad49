"""The Python client of the primlabel labeling service (proto/primlabel/v1/labeling.proto), the
same protocol as the C++ client (client/src/client.cpp):

    client = primlabel.Client("127.0.0.1:50051")
    result = client.label(xyz)   # xyz: (N, 3) float32 or float64
    result.labels[i]             # the taxonomy class of xyz[i]

Every call has a deadline (the client's unless the call gives one) covering all its attempts.
Calls failing with UNAVAILABLE or RESOURCE_EXHAUSTED (the server restarting, or its queue full)
are retried with exponential backoff and jitter within that deadline; labeling is a pure function
of the request, so a retry is safe. Failures raise PrimlabelError with the gRPC status.
"""

from __future__ import annotations

import enum
import functools
import math
import os
import time
import warnings
from dataclasses import dataclass

import grpc
import numpy as np

from . import files
from .backoff import Backoff, BackoffPolicy
from .errors import DomainWarning, InvalidInput, PrimlabelError, ProtocolError
from .instances import Primitive, TabletopObject, TabletopTable
from .pcd import PointCloud
from .v1 import labeling_pb2, labeling_pb2_grpc
from .wire import (
    NO_SEGMENT,
    LabelAssembler,
    as_points,
    decode_health_status,
    encode_health_request,
)

DEFAULT_ADDRESS = "127.0.0.1:50051"
DEFAULT_CHUNK_POINTS = 65536  # points per streamed request message, as the C++ client
RETRIED_CODES = frozenset({grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.RESOURCE_EXHAUSTED})
_NON_FINITE = {
    "drop": labeling_pb2.NON_FINITE_DROP,  # NaN/Inf points are labeled 0 and counted
    "reject": labeling_pb2.NON_FINITE_REJECT,  # they fail the call with INVALID_ARGUMENT
}
_METRES_PER_UNIT = {"m": 1.0, "cm": 0.01, "mm": 0.001}


@dataclass(frozen=True)
class Tls:
    """TLS to the server. Paths of PEM files; no ca_file = the system's roots. cert_file and
    key_file together give mutual TLS."""

    ca_file: str | None = None
    cert_file: str | None = None
    key_file: str | None = None
    server_name_override: str | None = None  # expected name in the server certificate (tests)


@dataclass(frozen=True)
class ClassInfo:
    id: int  # taxonomy id, as in Result.labels
    name: str


def probability_field_name(name: str, class_id: int) -> str:
    """The per-class field name every primlabel output uses (PCD, PLY, the ROS node):
    "prob_<class>" with characters outside [A-Za-z0-9_] as "_", "prob_<id>" without a name."""
    if not name:
        return f"prob_{class_id}"
    return "prob_" + "".join(c if (c.isascii() and c.isalnum()) or c == "_" else "_" for c in name)


UNKNOWN_CLASS = ClassInfo(0, "unknown")  # label 0: no class (and dropped NaN points)


@dataclass
class Result:
    """The labels of one cloud, in the order of its points."""

    labels: np.ndarray  # (N,) uint32 taxonomy class id, 0 = unknown (and dropped NaN points)
    probabilities: np.ndarray | None  # (N, len(model_classes)) float32 when asked for
    descriptors: np.ndarray | None  # (N, summary.descriptor_dim) float32, NaN rows: none
    # Every class a label can be, by id: 0 (unknown) and the model's, so classes[label] names
    # any label: `result.classes[result.labels[i]].name`.
    classes: dict[int, ClassInfo]
    model_classes: list[ClassInfo]  # the model's classes: the columns of probabilities
    summary: labeling_pb2.LabelSummary  # model, version, counts, timings, domain warning
    # With primitives=True: (N,) uint32, the point's index into primitives, NO_SEGMENT if none.
    segments: np.ndarray | None = None
    # With objects=True: (N,) uint32, the point's table-top object: 0 the table, k objects[k - 1],
    # NO_OBJECT neither.
    object_ids: np.ndarray | None = None
    attempts: int = 1  # calls made, including retries

    @functools.cached_property
    def primitives(self) -> list[Primitive]:
        """The fitted instances (instances.Primitive), primitives[s] for segment id s."""
        names = {i: c.name for i, c in self.classes.items()}
        return [Primitive.from_message(p, names) for p in self.summary.primitives]

    @functools.cached_property
    def objects(self) -> list[TabletopObject]:
        """The table-top objects (instances.TabletopObject), objects[k - 1] for object id k."""
        return [TabletopObject.from_message(o) for o in self.summary.objects]

    @functools.cached_property
    def table(self) -> TabletopTable | None:
        """The table the objects stand on (instances.TabletopTable), None when none was found
        (summary.no_table_reason says why)."""
        return TabletopTable.from_message(self.summary.table) if self.summary.HasField(
            "table") else None

    @property
    def domain_warning(self) -> str:
        """The summary's domain_warning ("" when none): set when the model labeled a cloud
        outside its training domain; the call also warned (DomainWarning)."""
        return self.summary.domain_warning

    @property
    def class_ids(self) -> np.ndarray:
        """The ids of model_classes: class_ids[k] is the class of probabilities[:, k]."""
        return np.array([c.id for c in self.model_classes], dtype=np.uint32)

    def probability_fields(self) -> dict[str, np.ndarray]:
        """The probabilities as one (N,) column per class, named as every primlabel output names
        them ("prob_plane", ...): `cloud.fields.update(result.probability_fields())`. Empty
        without probabilities."""
        if self.probabilities is None:
            return {}
        return {probability_field_name(c.name, c.id): np.ascontiguousarray(self.probabilities[:, k])
                for k, c in enumerate(self.model_classes)}

    @property
    def model_choice(self) -> str:
        """How the server chose the model: "named" (by the call), "domain" (the model whose
        training domain fits the cloud) or "default" (the repository's default, when no domain
        decided); model_choice_reason says what decided."""
        return _MODEL_CHOICES.get(self.summary.model_choice, "")

    @property
    def model_choice_reason(self) -> str:
        return self.summary.model_choice_reason


class HealthStatus(enum.IntEnum):
    UNKNOWN = 0
    SERVING = 1
    NOT_SERVING = 2
    SERVICE_UNKNOWN = 3


def _read_pem(path: str | None, what: str) -> bytes | None:
    if not path:
        return None
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise InvalidInput(f"{path}: cannot read the {what} file: {e.strerror}") from None
    if not data:
        raise InvalidInput(f"{path}: the {what} file is empty")
    return data


def _positive_or_zero(value, what: str) -> float:
    number = 0.0 if value is None else float(value)
    if not math.isfinite(number) or number < 0:
        raise InvalidInput(f"{what} must be a finite number >= 0, got {value!r}")
    return number


@dataclass
class _Call:
    """What one labeling call sends: the header and the packed points."""

    header: labeling_pb2.ScanHeader
    xyz: np.ndarray
    normals: np.ndarray | None
    chunk_points: int
    want_descriptors: bool
    want_probabilities: bool
    want_segments: bool
    want_objects: bool = False

    def chunk(self, first: int, end: int | None) -> labeling_pb2.PointChunk:
        chunk = labeling_pb2.PointChunk(xyz=self.xyz[first:end].tobytes())
        if self.normals is not None:
            chunk.normals = self.normals[first:end].tobytes()
        return chunk

    def requests(self):
        yield labeling_pb2.LabelRequest(header=self.header)
        for first in range(0, len(self.xyz), self.chunk_points):
            yield labeling_pb2.LabelRequest(chunk=self.chunk(first, first + self.chunk_points))
        yield labeling_pb2.LabelRequest(end=labeling_pb2.EndOfScan())

    def assembler(self) -> LabelAssembler:
        return LabelAssembler(len(self.xyz), self.want_descriptors, self.want_probabilities,
                              self.want_segments, self.want_objects)


def _points_of(cloud):
    """What label() sends for `cloud`: a pcd.PointCloud as it is, the file a path names read
    into one (PCD or PLY, by the extension, as the CLI reads it), the points of an Open3D cloud
    (open3d.geometry.PointCloud's .points, open3d.t.geometry.PointCloud's .point.positions; its
    normals and colours are not sent), else the array itself. Open3D is never imported: any
    object with such points will do."""
    if isinstance(cloud, (str, os.PathLike)):
        try:
            return files.read(cloud)
        except ValueError as e:  # PcdError, PlyError, UnsupportedFormat
            raise InvalidInput(str(e)) from e
    if isinstance(cloud, (np.ndarray, PointCloud)):
        return cloud
    attributes = getattr(cloud, "point", None)  # open3d.t.geometry.PointCloud: a tensor map
    if attributes is not None and not isinstance(attributes, np.ndarray):
        try:
            positions = attributes["positions"] if "positions" in attributes else None
        except TypeError:
            positions = getattr(attributes, "positions", None)
        if positions is None:  # a tensor cloud without points
            return np.zeros((0, 3), np.float32)
        if hasattr(positions, "cpu"):  # a tensor on another device
            positions = positions.cpu()
        return positions.numpy() if hasattr(positions, "numpy") else np.asarray(positions)
    points = getattr(cloud, "points", None)  # open3d.geometry.PointCloud: Vector3dVector
    if points is not None:
        return np.asarray(points)
    return cloud


_MODEL_CHOICES = {
    labeling_pb2.MODEL_CHOICE_NAMED: "named",
    labeling_pb2.MODEL_CHOICE_DOMAIN: "domain",
    labeling_pb2.MODEL_CHOICE_DEFAULT: "default",
}


def _result(assembled_and_summary, attempts: int) -> Result:
    assembled, summary = assembled_and_summary
    labels, descriptor_rows, probability_rows, classes, segments, objects = assembled
    if summary.domain_warning:  # plausible-looking labels from a model of another sensor
        warnings.warn(f"model {summary.model}: {summary.domain_warning}", DomainWarning,
                      stacklevel=3)
    model_classes = [ClassInfo(int(i), name) for i, name in classes]
    by_id = {UNKNOWN_CLASS.id: UNKNOWN_CLASS}
    by_id.update((c.id, c) for c in model_classes)
    for count in summary.class_counts:  # a label outside the model's classes still has a name
        by_id.setdefault(int(count.class_id), ClassInfo(int(count.class_id), count.name))
    return Result(
        labels=labels,
        probabilities=probability_rows,
        descriptors=descriptor_rows,
        classes=by_id,
        model_classes=model_classes,
        summary=summary,
        segments=segments,
        object_ids=objects,
        attempts=attempts,
    )


class Client:
    """A channel to one primlabel server; thread-safe, reuse it for every call.

    address: HOST:PORT. token: the bearer token, sent as "authorization: Bearer <token>".
    tls: None (plaintext: loopback or a trusted network), True (the system's roots) or Tls.
    deadline: seconds per call, including its retries. retry_attempts: attempts in all on
    UNAVAILABLE / RESOURCE_EXHAUSTED (1 = no retry).
    """

    def __init__(
        self,
        address: str = DEFAULT_ADDRESS,
        token: str | None = None,
        tls: Tls | bool | None = None,
        deadline: float = 60.0,
        retry_attempts: int = 4,
        backoff: BackoffPolicy = BackoffPolicy(),
        max_receive_message_bytes: int = 64 << 20,
    ):
        self.address = address
        self.deadline = _positive_or_zero(deadline, "deadline")
        if self.deadline == 0:
            raise InvalidInput("deadline must be > 0 seconds")
        if retry_attempts < 1:
            raise InvalidInput(f"retry_attempts must be >= 1, got {retry_attempts}")
        self.retry_attempts = int(retry_attempts)
        self._backoff = backoff
        self._metadata = (("authorization", f"Bearer {token}"),) if token else ()
        options = [
            # Keepalive as the server expects it, so a dead peer is noticed between scans.
            ("grpc.keepalive_time_ms", 30_000),
            ("grpc.keepalive_timeout_ms", 10_000),
            ("grpc.keepalive_permit_without_calls", 1),
            ("grpc.http2.max_pings_without_data", 0),
            # A restarted server is found within 2 s, not gRPC's default of up to two minutes.
            ("grpc.min_reconnect_backoff_ms", 100),
            ("grpc.initial_reconnect_backoff_ms", 100),
            ("grpc.max_reconnect_backoff_ms", 2_000),
            ("grpc.max_receive_message_length", int(max_receive_message_bytes)),
            # The client retries itself; gRPC's own retries would multiply the attempts.
            ("grpc.enable_retries", 0),
        ]
        if tls:
            settings = tls if isinstance(tls, Tls) else Tls()
            cert = _read_pem(settings.cert_file, "client certificate")
            key = _read_pem(settings.key_file, "client key")
            if (cert is None) != (key is None):
                raise InvalidInput("mutual TLS needs both a client certificate and its key")
            credentials = grpc.ssl_channel_credentials(
                root_certificates=_read_pem(settings.ca_file, "CA certificate"),
                private_key=key,
                certificate_chain=cert,
            )
            if settings.server_name_override:
                options.append(("grpc.ssl_target_name_override", settings.server_name_override))
            self._channel = grpc.secure_channel(address, credentials, options=options)
        else:
            self._channel = grpc.insecure_channel(address, options=options)
        self._labeler = labeling_pb2_grpc.LabelerStub(self._channel)
        self._health = self._channel.unary_unary("/grpc.health.v1.Health/Check")

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -----------------------------------------------------------------------------------------

    def _with_retries(self, timeout: float, attempt):
        """Runs attempt(remaining_seconds) until it succeeds, fails with a code not retried,
        the attempts are used up or the deadline would pass during the backoff. Returns
        (its value, attempts)."""
        deadline_at = time.monotonic() + timeout
        backoff = Backoff(self._backoff)
        n = 0
        while True:
            n += 1
            remaining = max(deadline_at - time.monotonic(), 0.001)
            try:
                return attempt(remaining), n
            except grpc.RpcError as e:
                code, message = e.code(), e.details() or ""
            except ProtocolError as e:
                raise PrimlabelError(grpc.StatusCode.DATA_LOSS, str(e), n) from None
            if code in RETRIED_CODES and n < self.retry_attempts:
                delay = backoff.next()
                if time.monotonic() + delay < deadline_at:
                    time.sleep(delay)
                    continue
            raise PrimlabelError(code, message, n)

    def label(
        self,
        xyz,
        normals=None,
        model: str | None = None,
        voxel_size: float | None = None,
        probabilities: bool = False,
        descriptors: bool = False,
        tabletop_only: bool = False,
        scan_id: str | None = None,
        **options,
    ) -> Result:
        """Streams the points (Labeler.Label) in messages of chunk_points and returns their
        labels in input order.

        xyz: (N, 3) array, float32 or float64 (sent as float32), an (H, W, 3) organised frame,
        a pcd.PointCloud (its xyz, its VIEWPOINT unless viewpoint is given, and its WIDTH x
        HEIGHT when organised), a path (str or pathlib.Path) to a .pcd or .ply file (read with
        primlabel.read and sent as its PointCloud, as the CLI sends it), or an Open3D cloud
        (open3d.geometry.PointCloud or open3d.t.geometry.PointCloud: its points only, from the
        origin unless viewpoint is given). normals: (N, 3), sent so the server skips normal
        estimation. model: None = the model whose training domain fits the cloud (the sensor and
        image size, then spacing and noise), else the repository's default (Result.model_choice
        says which); a named model used outside its domain warns (DomainWarning). voxel_size:
        > 0 downsamples before features (labels still cover every input point); None = the
        model's.

        Keyword-only options: model_version; viewpoint, the sensor origin (x, y, z) the normals
        face (default: the origin; it changes the labels, convex or concave, so pass the
        scan's); normal_radius, feature_radius (> 0: override, where the model allows);
        non_finite, "drop" (NaN/Inf points get label 0) or "reject" (the call fails with
        INVALID_ARGUMENT); primitives, True to group the labels into same-class segments fitted
        with their class's model (Result.segments, Result.primitives); objects, True (with
        tabletop_only) for the table and its objects as instances (Result.table,
        Result.objects, per point Result.object_ids); every_point, True to describe and infer
        every point: no plane cascade (summary.cascaded_points stays 0), the model's exact labels
        everywhere, slower; units, "m" (default), "cm" or "mm": the unit of xyz and viewpoint,
        scaled to metres on the way out (primitives and objects come back in metres); shape,
        (height, width) of an organised frame whose container does not keep it (an Open3D cloud
        made with project_valid_depth_only=False): it lets the server pick the camera's model;
        chunk_points, response_chunk_points; deadline (seconds).
        """
        call, timeout = self._prepare(xyz, normals, model, voxel_size, probabilities, descriptors,
                                      tabletop_only, scan_id, **options)

        def attempt(remaining: float):
            # A fresh assembler and request stream per attempt: a retry resends the whole scan.
            assembler = call.assembler()
            responses = self._labeler.Label(call.requests(), timeout=remaining,
                                            metadata=self._metadata)
            summary = None
            try:
                for response in responses:
                    if response.HasField("chunk"):
                        assembler.add(response.chunk)
                    elif response.HasField("summary"):
                        summary = response.summary
            except ProtocolError:
                responses.cancel()
                raise
            if summary is None:
                raise ProtocolError("the server closed the stream without a summary")
            return assembler.finish(summary), summary

        return _result(*self._with_retries(timeout, attempt))

    def label_unary(
        self,
        xyz,
        normals=None,
        model: str | None = None,
        voxel_size: float | None = None,
        probabilities: bool = False,
        descriptors: bool = False,
        tabletop_only: bool = False,
        scan_id: str | None = None,
        **options,
    ) -> Result:
        """label() in one request and one answer (Labeler.LabelCloud): fewer round trips for a
        small cloud, but the whole cloud and answer must fit the server's message limit (about
        4M points; bigger ones fail with RESOURCE_EXHAUSTED: use label()). The same arguments;
        chunk_points and response_chunk_points do not apply."""
        for streamed_only in ("chunk_points", "response_chunk_points"):
            if streamed_only in options:
                raise InvalidInput(f"{streamed_only} applies to label() only")
        call, timeout = self._prepare(xyz, normals, model, voxel_size, probabilities, descriptors,
                                      tabletop_only, scan_id, **options)
        request = labeling_pb2.LabelCloudRequest(header=call.header, points=call.chunk(0, None))

        def attempt(remaining: float):
            response = self._labeler.LabelCloud(request, timeout=remaining,
                                                metadata=self._metadata)
            assembler = call.assembler()
            if response.HasField("result"):
                assembler.add(response.result)
            return assembler.finish(response.summary), response.summary

        return _result(*self._with_retries(timeout, attempt))

    def _prepare(
        self,
        xyz,
        normals,
        model,
        voxel_size,
        probabilities,
        descriptors,
        tabletop_only,
        scan_id,
        *,
        model_version: str | None = None,
        viewpoint=None,
        normal_radius: float | None = None,
        feature_radius: float | None = None,
        non_finite: str = "drop",
        primitives: bool = False,
        objects: bool = False,
        every_point: bool = False,
        chunk_points: int = DEFAULT_CHUNK_POINTS,
        response_chunk_points: int = 0,
        deadline: float | None = None,
        units: str = "m",
        shape=None,
    ) -> tuple[_Call, float]:
        """The checked request of one labeling call, and its deadline in seconds."""
        frame = (0, 0)  # width, height of an organised frame: it lets the server pick the model
        xyz = _points_of(xyz)
        if isinstance(xyz, PointCloud):  # its points, seen from its VIEWPOINT as the CLI does
            if viewpoint is None:
                viewpoint = xyz.viewpoint[:3]
            if xyz.organized:
                frame = (xyz.width or len(xyz) // xyz.height, xyz.height)
            xyz = xyz.xyz
        elif np.ndim(xyz) == 3 and np.shape(xyz)[2] == 3:  # an (H, W, 3) image of points
            frame = (np.shape(xyz)[1], np.shape(xyz)[0])
            xyz = np.reshape(xyz, (-1, 3))
        points = as_points(xyz, "xyz")
        if shape is not None:  # an organised frame whose shape the container lost (Open3D)
            try:
                height, width = (int(v) for v in shape)
            except (TypeError, ValueError):
                raise InvalidInput(f"shape must be (height, width), got {shape!r}") from None
            if height < 1 or width < 1 or height * width != len(points):
                raise InvalidInput(
                    f"shape {height}x{width} does not hold the cloud's {len(points)} points"
                )
            frame = (width, height)
        if units not in _METRES_PER_UNIT:
            raise InvalidInput(f"units must be 'm', 'cm' or 'mm', got {units!r}")
        scale = _METRES_PER_UNIT[units]
        if scale != 1.0:  # the server works in metres; the caller's array is left as it was
            points = (points * np.float32(scale)).astype(np.float32)
        sent_normals = None if normals is None else as_points(normals, "normals", len(points))
        if non_finite not in _NON_FINITE:
            raise InvalidInput(f"non_finite must be 'drop' or 'reject', got {non_finite!r}")
        if int(chunk_points) < 1:
            raise InvalidInput(f"chunk_points must be >= 1, got {chunk_points}")
        if not 0 <= int(response_chunk_points) <= 0xFFFFFFFF:
            raise InvalidInput(f"response_chunk_points out of range: {response_chunk_points}")
        origin = np.zeros(3) if viewpoint is None else np.asarray(viewpoint, dtype=np.float64)
        if origin.shape != (3,):
            raise InvalidInput(f"viewpoint must be (x, y, z), got shape {origin.shape}")
        origin = origin * scale

        header = labeling_pb2.ScanHeader(
            model=model or "",
            model_version=model_version or "",
            scan_id=scan_id or "",
            viewpoint=labeling_pb2.Vec3(x=origin[0], y=origin[1], z=origin[2]),
            options=labeling_pb2.LabelOptions(
                return_descriptors=bool(descriptors),
                return_probabilities=bool(probabilities),
                tabletop_only=bool(tabletop_only),
                voxel_size=_positive_or_zero(voxel_size, "voxel_size"),
                normal_radius=_positive_or_zero(normal_radius, "normal_radius"),
                feature_radius=_positive_or_zero(feature_radius, "feature_radius"),
                non_finite=_NON_FINITE[non_finite],
                response_chunk_points=int(response_chunk_points),
                return_primitives=bool(primitives),
                return_objects=bool(objects),
                every_point=bool(every_point),
            ),
            layout=labeling_pb2.PointLayout(normals=sent_normals is not None,
                                            width=frame[0] if frame[1] > 1 else 0,
                                            height=frame[1] if frame[1] > 1 else 0),
            expected_points=len(points),
        )
        if objects and not tabletop_only:
            raise InvalidInput("objects=True needs tabletop_only=True (the table-top stage's)")
        call = _Call(header, points, sent_normals, int(chunk_points), bool(descriptors),
                     bool(probabilities), bool(primitives), bool(objects))
        timeout = self.deadline if deadline is None else _positive_or_zero(deadline, "deadline")
        return call, timeout

    def models(self) -> list:
        """The models the server serves (labeling_pb2.ModelInfo), the default one flagged."""
        response, _ = self._with_retries(
            self.deadline,
            lambda remaining: self._labeler.ListModels(
                labeling_pb2.ListModelsRequest(), timeout=remaining, metadata=self._metadata
            ),
        )
        return list(response.models)

    def model_metadata(self, model: str, version: str = ""):
        """One model's classes, feature and graph parameters and training summary."""
        request = labeling_pb2.GetModelMetadataRequest(model=model, version=version)
        response, _ = self._with_retries(
            self.deadline,
            lambda remaining: self._labeler.GetModelMetadata(
                request, timeout=remaining, metadata=self._metadata
            ),
        )
        return response

    def health(self, service: str = "") -> HealthStatus:
        """grpc.health.v1 Check of `service` ("" = the server as a whole). Raises PrimlabelError
        (UNAVAILABLE) when the server cannot be reached."""
        request = encode_health_request(service)
        status, _ = self._with_retries(
            self.deadline,
            lambda remaining: decode_health_status(
                self._health(request, timeout=remaining, metadata=self._metadata)
            ),
        )
        return HealthStatus(status) if status <= 3 else HealthStatus.UNKNOWN
