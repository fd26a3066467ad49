"""PLY files to and from numpy through core/geometry's reader and writer (ply_io.cpp, bound as
primlabel._cloud_files): format ascii, binary_little_endian and binary_big_endian are read (the
first `vertex` element becomes the points), ascii and binary_little_endian written.

    cloud = primlabel.ply.read("scan_labeled.ply")   # a pcd.PointCloud
    cloud.xyz, cloud.label, cloud.fields["prob_plane"], cloud.fields["fpfh"]  # (N, 33)

Property mapping (cloud_io.hpp): x y z -> xyz; nx ny nz (or normal_x normal_y normal_z) ->
normals; curvature; label -> label (uint32; must be integers in 0..2^32-1); red green blue
[alpha] (uchar) -> rgb (uint32 packed 0xAARRGGBB as PCL packs it, opaque without alpha); every
other scalar property -> fields[name] as float32, except runs name_0, name_1, ..., name_k, which
become one (N, k + 1) field `name` (how primlabel writes a multi-value field such as fpfh). A PLY
has no viewpoint: the cloud's is the identity.
"""

from __future__ import annotations

import os

from . import _cloud_files
from .pcd import PointCloud, from_native, to_native


class PlyError(ValueError):
    """A file that cannot be read or a cloud that cannot be written; the message starts with
    the path."""


def read(path) -> PointCloud:
    """Reads a PLY file's vertices as a pcd.PointCloud; PlyError (a ValueError) says what is
    wrong with a malformed one."""
    path = os.fspath(path)
    try:
        return from_native(_cloud_files.read_ply(path), path, ply=True)
    except _cloud_files.IoError as e:
        raise PlyError(str(e)) from None


def write(path, cloud: PointCloud, encoding: str = "binary_little_endian") -> None:
    """Writes `cloud` as PLY (ascii or binary_little_endian) atomically; a multi-value field
    becomes the properties name_0 .. name_k."""
    path = os.fspath(path)
    try:
        _cloud_files.write_ply(path, **to_native(cloud), encoding=encoding)
    except _cloud_files.IoError as e:
        raise PlyError(str(e)) from None
