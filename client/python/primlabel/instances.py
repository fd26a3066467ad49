"""The instances of an answer as frozen dataclasses with numpy vectors: the fitted primitives
(Result.primitives), the table-top table (Result.table) and its objects (Result.objects). Fields
are the proto's (proto/primlabel/v1/labeling.proto), named alike; vectors are read-only float64
(3,) arrays, metres in the cloud's frame. Each keeps its message as `.message`, so nothing is
lost:

    for p in result.primitives:
        if p.kind == "cylinder":
            print(p.class_name, p.model.radius, p.model.axis, p.point_count, p.confidence)
    table = result.table      # None when none was found (summary.no_table_reason says why)
    table.normal, table.offset, table.hull          # (3,), float, (K, 3)
    for obj in result.objects:                      # objects[k - 1] for object id k
        obj.centroid, obj.bounds_min, obj.bounds_max, obj.height
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .v1 import labeling_pb2


def _vector(v) -> np.ndarray:
    array = np.array([v.x, v.y, v.z], dtype=np.float64)
    array.flags.writeable = False
    return array


def _vectors(vs) -> np.ndarray:
    array = np.array([[v.x, v.y, v.z] for v in vs], dtype=np.float64).reshape(-1, 3)
    array.flags.writeable = False
    return array


# The fitted models (labeling_pb2.PlaneModel ... LineModel). eq=False: numpy fields compare
# element-wise, so instances compare by identity.


@dataclass(frozen=True, eq=False)
class Plane:
    """normal . x + offset = 0, and the oriented rectangle its inliers cover: centred on
    `center`, extent_u along axis_u and extent_v along axis_v (extent_u >= extent_v)."""

    normal: np.ndarray
    offset: float
    center: np.ndarray
    axis_u: np.ndarray
    axis_v: np.ndarray
    extent_u: float
    extent_v: float

    @property
    def coefficients(self) -> np.ndarray:
        """(a, b, c, d) of a x + b y + c z + d = 0, as PCL's ModelCoefficients."""
        return np.append(self.normal, self.offset)


@dataclass(frozen=True, eq=False)
class Cylinder:
    """The axis through `center` (the middle of the inliers' extent along it), `height` long."""

    center: np.ndarray
    axis: np.ndarray
    radius: float
    height: float


@dataclass(frozen=True, eq=False)
class Sphere:
    center: np.ndarray
    radius: float


@dataclass(frozen=True, eq=False)
class Torus:
    """The tube's centre circle of radius major_radius around `axis` through `center`."""

    center: np.ndarray
    axis: np.ndarray
    major_radius: float
    minor_radius: float


@dataclass(frozen=True, eq=False)
class Line:
    """From center - length/2 * direction to center + length/2 * direction."""

    center: np.ndarray
    direction: np.ndarray
    length: float


_MODELS = {"plane": Plane, "cylinder": Cylinder, "sphere": Sphere, "torus": Torus, "line": Line}


def _model(message):
    """A model message as its dataclass: Vec3d fields as vectors, numbers as floats."""
    which = message.WhichOneof("model")
    if which is None:
        return None
    fitted = getattr(message, which)
    values = {}
    for f in dataclasses.fields(_MODELS[which]):
        value = getattr(fitted, f.name)
        values[f.name] = _vector(value) if hasattr(value, "x") else float(value)
    return _MODELS[which](**values)


def _kind_name(kind: int) -> str:
    try:
        return labeling_pb2.PrimitiveKind.Name(kind).removeprefix("PRIMITIVE_").lower()
    except ValueError:  # a kind newer than these stubs
        return f"kind_{kind}"


@dataclass(frozen=True, eq=False)
class Primitive:
    """One fitted instance: a connected segment of same-class points (Result.segments == its
    segment_id) and the model its class calls for."""

    segment_id: int  # its index in Result.primitives
    kind: str  # "plane", "cylinder", "sphere", "torus", "line" or "segment" (no model)
    class_id: int  # taxonomy class of its points
    class_name: str
    model: Plane | Cylinder | Sphere | Torus | Line | None  # None for kind "segment"
    point_count: int
    first_point: int  # the segment's lowest point index
    inliers: int  # points within the fit's distance band
    rms: float  # of the inliers' distances to the model (m)
    confidence: float  # [0, 1]: inlier share times the model's coverage; 0 without a model
    centroid: np.ndarray
    bounds_min: np.ndarray  # axis-aligned
    bounds_max: np.ndarray
    message: labeling_pb2.Primitive = field(repr=False)

    @property
    def parameters(self) -> dict:
        """The model's parameters by name ({"center": ..., "radius": ...}); {} without one."""
        if self.model is None:
            return {}
        return {f.name: getattr(self.model, f.name) for f in dataclasses.fields(self.model)}

    @classmethod
    def from_message(cls, message, class_names: dict | None = None) -> Primitive:
        return cls(
            segment_id=int(message.segment_id),
            kind=_kind_name(message.kind),
            class_id=int(message.class_id),
            class_name=(class_names or {}).get(int(message.class_id), ""),
            model=_model(message),
            point_count=int(message.point_count),
            first_point=int(message.first_point),
            inliers=int(message.inliers),
            rms=float(message.rms),
            confidence=float(message.confidence),
            centroid=_vector(message.centroid),
            bounds_min=_vector(message.bounds_min),
            bounds_max=_vector(message.bounds_max),
            message=message,
        )


@dataclass(frozen=True, eq=False)
class TabletopTable:
    """The supporting table: the plane normal . x + offset = 0 (normal on the objects' side),
    its boundary on the plane (convex, counter-clockwise about the normal) and the primitives
    more than half of whose points lie on it."""

    normal: np.ndarray
    offset: float
    hull: np.ndarray  # (K, 3)
    point_count: int  # Result.object_ids == 0
    primitive_ids: tuple  # indices into Result.primitives, ascending
    message: labeling_pb2.TabletopTable = field(repr=False)

    @property
    def coefficients(self) -> np.ndarray:
        """(a, b, c, d) of a x + b y + c z + d = 0, as PCL's ModelCoefficients."""
        return np.append(self.normal, self.offset)

    def height_of(self, xyz) -> np.ndarray:
        """Signed distances of (N, 3) points above the table plane (> 0 on the objects' side)."""
        return np.asarray(xyz, dtype=np.float64) @ self.normal + self.offset

    @classmethod
    def from_message(cls, message) -> TabletopTable:
        return cls(
            normal=_vector(message.normal),
            offset=float(message.offset),
            hull=_vectors(message.hull),
            point_count=int(message.point_count),
            primitive_ids=tuple(int(i) for i in message.primitive_ids),
            message=message,
        )


@dataclass(frozen=True, eq=False)
class TabletopObject:
    """One object on the table."""

    object_id: int  # >= 1, as in Result.object_ids; Result.objects[object_id - 1]
    point_count: int
    centroid: np.ndarray
    bounds_min: np.ndarray  # axis-aligned
    bounds_max: np.ndarray
    height: float  # of its highest point above the table plane
    primitive_ids: tuple  # indices into Result.primitives, ascending; () without primitives
    message: labeling_pb2.TabletopObject = field(repr=False)

    @property
    def extent(self) -> np.ndarray:
        """bounds_max - bounds_min: the axis-aligned box's size."""
        return self.bounds_max - self.bounds_min

    @classmethod
    def from_message(cls, message) -> TabletopObject:
        return cls(
            object_id=int(message.object_id),
            point_count=int(message.point_count),
            centroid=_vector(message.centroid),
            bounds_min=_vector(message.bounds_min),
            bounds_max=_vector(message.bounds_max),
            height=float(message.height),
            primitive_ids=tuple(int(i) for i in message.primitive_ids),
            message=message,
        )
