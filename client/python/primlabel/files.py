"""Point cloud files by their extension: primlabel.read("scan.pcd") or ("scan_labeled.ply")."""

from __future__ import annotations

import os

from . import pcd, ply

READERS = {".pcd": pcd.read, ".ply": ply.read}


class UnsupportedFormat(ValueError):
    """A file whose extension names no format primlabel reads; the message starts with the
    path."""


def read(path) -> pcd.PointCloud:
    """Reads a PCD (pcd.read) or PLY (ply.read) file as a pcd.PointCloud, by its extension
    (.pcd or .ply, any case). Malformed files raise pcd.PcdError or ply.PlyError, an unknown
    extension UnsupportedFormat: all three are ValueErrors."""
    path = os.fspath(path)
    extension = os.path.splitext(path)[1].lower()
    reader = READERS.get(extension)
    if reader is None:
        raise UnsupportedFormat(f"{path}: unknown point cloud format "
                                f"'{extension or '(no extension)'}' (.pcd and .ply are read)")
    return reader(path)
