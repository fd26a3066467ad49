"""PCD v0.7 files to and from numpy through core/geometry's reader and writer (pcd_io.cpp, bound
as primlabel._cloud_files), the code the service and its tools use: DATA ascii, binary and
binary_compressed (LZF through liblzf), read and written.

    cloud = primlabel.pcd.read("scan.pcd")
    cloud.xyz          # (N, 3); organised clouds keep their NaN pixels, width and height
    cloud.grid(cloud.xyz)  # (height, width, 3)
    primlabel.pcd.write("out.pcd", cloud, encoding="binary")

Field mapping (cloud_io.hpp): x y z -> xyz (float32); normal_x normal_y normal_z -> normals;
curvature; label -> label (uint32; must be integers in 0..2^32-1); rgb / rgba -> rgb (uint32, the
4 bytes bit for bit, as PCL packs 0xAARRGGBB); every other field -> fields[name] as float32, (N,)
for COUNT 1 and (N, COUNT) otherwise; COUNT 1 columns name_0 .. name_k beside a field `name` of
COUNT k + 1 are its copies for one-value-per-field readers (Open3D), which write() adds and read()
folds back. "_" padding fields are skipped. Every size the header declares is checked against the
bytes really in the file before anything proportional to it is allocated.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from . import _cloud_files, labeled

_IDENTITY_VIEWPOINT = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)


class PcdError(ValueError):
    """A file that cannot be read or a cloud that cannot be written; the message starts with
    the path."""


@dataclass
class PointCloud:
    xyz: np.ndarray  # (N, 3) float32
    normals: np.ndarray | None = None  # (N, 3)
    curvature: np.ndarray | None = None  # (N,)
    label: np.ndarray | None = None  # (N,) uint32
    rgb: np.ndarray | None = None  # (N,) uint32 packed 0xAARRGGBB
    fields: dict = field(default_factory=dict)  # name -> (N,) or (N, COUNT) float32
    width: int | None = None  # points per row; None = one row of all points
    height: int = 1  # rows; > 1 means organised (e.g. a 640x480 depth frame)
    viewpoint: tuple = _IDENTITY_VIEWPOINT  # tx ty tz qw qx qy qz, as the VIEWPOINT line
    # A labeled file's classes, label id -> name (primlabel.labeled: its header's `classes` tag
    # or the .classes.json beside it); None when it says nothing. Not written by write().
    classes: dict | None = None

    def __len__(self) -> int:
        return len(self.xyz)

    @property
    def organized(self) -> bool:
        return self.height > 1

    def grid(self, values: np.ndarray) -> np.ndarray:
        """A per-point array as (height, width, ...) pixels."""
        width = len(self) if self.width is None else self.width
        return np.asarray(values).reshape((self.height, width) + np.shape(values)[1:])


def from_native(values: dict, path: str, ply: bool = False) -> PointCloud:
    """The PointCloud of what _cloud_files.read_pcd or read_ply returned for `path`."""
    return PointCloud(
        xyz=values["xyz"], normals=values["normals"], curvature=values["curvature"],
        label=values["labels"], rgb=values["rgba"], fields=dict(values["fields"]),
        width=values["width"], height=max(values["height"], 1),
        viewpoint=tuple(values["viewpoint"]), classes=labeled.classes(path, ply=ply))


def to_native(cloud: PointCloud) -> dict:
    """`cloud` as the keyword arguments of _cloud_files.write_pcd and write_ply."""
    return dict(
        xyz=np.asarray(cloud.xyz), normals=cloud.normals, curvature=cloud.curvature,
        labels=cloud.label, rgba=cloud.rgb, fields=list(cloud.fields.items()),
        width=None if cloud.width is None else int(cloud.width), height=int(cloud.height),
        viewpoint=[float(v) for v in cloud.viewpoint])


def read(path: str) -> PointCloud:
    """Reads a PCD file; PcdError (a ValueError) says what is wrong with a malformed one. PLY
    files: primlabel.ply.read, or primlabel.read for either by the extension."""
    path = os.fspath(path)
    try:
        return from_native(_cloud_files.read_pcd(path), path)
    except _cloud_files.IoError as e:
        raise PcdError(str(e)) from None


def write(path: str, cloud: PointCloud, encoding: str = "binary") -> None:
    """Writes `cloud` as PCD v0.7, DATA ascii, binary or binary_compressed (little-endian; LZF
    through liblzf), atomically (a temporary file beside `path` renamed over it). Values are
    written as the service's files hold them: xyz, normals, curvature and fields as float32."""
    path = os.fspath(path)
    try:
        _cloud_files.write_pcd(path, **to_native(cloud), encoding=encoding)
    except _cloud_files.IoError as e:
        raise PcdError(str(e)) from None
