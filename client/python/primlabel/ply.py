"""PLY files to numpy, read as core/geometry's reader does (ply_io.cpp): format ascii,
binary_little_endian and binary_big_endian; the first `vertex` element becomes the points.

    cloud = primlabel.ply.read("scan_labeled.ply")   # a pcd.PointCloud
    cloud.xyz, cloud.label, cloud.fields["prob_plane"], cloud.fields["fpfh"]  # (N, 33)

Property mapping: x y z -> xyz; nx ny nz (or normal_x normal_y normal_z) -> normals; curvature;
label -> label (uint32; must be integers in 0..2^32-1); red green blue [alpha] (uchar) -> rgb
(uint32 packed 0xAARRGGBB as PCL packs it, opaque without alpha); every other scalar property ->
fields[name], (N,) in its stored type, except runs name_0, name_1, ..., name_k (k >= 1) with no
property `name`, which become one (N, k + 1) field `name` (how primlabel writes a multi-value
field such as fpfh). Vertex list properties and the elements other than the vertex are skipped.
A PLY has no viewpoint: the cloud's is the identity, as the C++ reader's. Every count the header
declares is checked against the bytes really in the file before anything proportional to it is
allocated.
"""

from __future__ import annotations

import os
import re

import numpy as np

from . import labeled
from .pcd import PointCloud, ascii_values, checked_labels

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
_NORMALS = (("nx", "ny", "nz"), ("normal_x", "normal_y", "normal_z"))
_COLOURS = (("red", 16), ("green", 8), ("blue", 0), ("alpha", 24))


class PlyError(ValueError):
    """A file that cannot be read; the message starts with the path."""


class _Property:
    def __init__(self, name: str, kind: str, length_kind: str | None, line: int):
        self.name = name
        self.kind = kind  # numpy type code without byte order, e.g. "f4"
        self.length_kind = length_kind  # the list length's type; None for a scalar
        self.line = line

    @property
    def is_list(self) -> bool:
        return self.length_kind is not None


class _Element:
    def __init__(self, name: str, count: int, line: int):
        self.name = name
        self.count = count
        self.properties: list[_Property] = []
        self.line = line

    @property
    def has_lists(self) -> bool:
        return any(p.is_list for p in self.properties)

    def scalars(self) -> list:
        return [p for p in self.properties if not p.is_list]


def _parse_header(path: str, raw: bytes):
    def fail(line: int, message: str):
        raise PlyError(f"{path}: header line {line}: {message}")

    if not raw:
        raise PlyError(f"{path}: empty file, not a PLY file")
    if not (raw.startswith(b"ply\n") or raw.startswith(b"ply\r\n")):
        raise PlyError(f"{path}: not a PLY file (it does not start with a 'ply' line)")
    fmt, elements = None, []
    pos, line_number = 0, 0
    while pos < len(raw):
        end = raw.find(b"\n", pos)
        end = len(raw) if end < 0 else end
        tokens = raw[pos:end].decode("latin-1").split()
        pos = end + 1
        line_number += 1
        if line_number == 1 or not tokens or tokens[0] in ("comment", "obj_info"):
            continue
        keyword = tokens[0]
        if keyword == "format":
            if fmt is not None:
                fail(line_number, "duplicate format line")
            if len(tokens) != 3:
                fail(line_number, "format needs a kind and a version")
            if tokens[1] not in _FORMATS:
                raise PlyError(f"{path}: unsupported format '{tokens[1]}' (ascii, "
                               "binary_little_endian and binary_big_endian are read)")
            fmt = tokens[1]
        elif keyword == "element":
            if len(tokens) != 3 or not re.fullmatch(r"[0-9]+", tokens[2]):
                fail(line_number, "element needs a name and a non-negative count")
            elements.append(_Element(tokens[1], int(tokens[2]), line_number))
        elif keyword == "property":
            if not elements:
                fail(line_number, "property before any element")
            if len(tokens) == 5 and tokens[1] == "list":
                if tokens[2] not in _TYPES or _TYPES[tokens[2]][0] == "f":
                    fail(line_number, f"list length type '{tokens[2]}' is not an integer type")
                if tokens[3] not in _TYPES:
                    fail(line_number, f"unknown property type '{tokens[3]}'")
                prop = _Property(tokens[4], _TYPES[tokens[3]], _TYPES[tokens[2]], line_number)
            elif len(tokens) == 3 and tokens[1] != "list":
                if tokens[1] not in _TYPES:
                    fail(line_number, f"unknown property type '{tokens[1]}'")
                prop = _Property(tokens[2], _TYPES[tokens[1]], None, line_number)
            else:
                fail(line_number, "property needs a type and a name")
            elements[-1].properties.append(prop)
        elif keyword == "end_header":
            if fmt is None:
                fail(line_number, "missing format line before end_header")
            return fmt, elements, min(pos, len(raw))
        else:
            fail(line_number, f"unknown header keyword '{keyword}'")
    raise PlyError(f"{path}: header: missing end_header line")


def _check_vertex(path: str, vertex: _Element) -> None:
    seen = {}
    for p in vertex.properties:
        if p.name in seen:
            raise PlyError(f"{path}: header line {p.line}: vertex property '{p.name}' is "
                           "listed twice")
        seen[p.name] = p
    for name in ("x", "y", "z", "nx", "ny", "nz", "normal_x", "normal_y", "normal_z",
                 "curvature", "label", "red", "green", "blue", "alpha"):
        if name in seen and seen[name].is_list:
            raise PlyError(f"{path}: header line {seen[name].line}: vertex property '{name}' "
                           "must not be a list")
    if not all(axis in seen for axis in "xyz"):
        raise PlyError(f"{path}: header line {vertex.line}: vertex element lacks property x, "
                       "y or z")
    if all(c in seen for c in ("red", "green", "blue")):
        for name in ("red", "green", "blue", "alpha"):
            if name in seen and seen[name].kind != "u1":
                raise PlyError(f"{path}: header line {seen[name].line}: colour property "
                               f"'{name}' must be uchar")


# ---------------------------------------------------------------------------------------------
# Binary


def _record_dtype(properties: list, order: str) -> np.dtype:
    return np.dtype([(f"p{i}", order + p.kind) for i, p in enumerate(properties)])


class _BinaryWalker:
    """Moves over binary records; elements with lists are walked record by record."""

    def __init__(self, path: str, data: bytes, order: str):
        self.path, self.data, self.order, self.pos = path, data, order, 0

    def truncated(self, element: _Element, record: int):
        raise PlyError(f"{self.path}: truncated binary data in element '{element.name}' at "
                       f"record {record} of {element.count}")

    def skip(self, element: _Element) -> None:
        if not element.has_lists:
            record_size = _record_dtype(element.properties, self.order).itemsize
            if element.count * record_size > len(self.data) - self.pos:
                self.truncated(element, (len(self.data) - self.pos) // max(record_size, 1))
            self.pos += element.count * record_size
            return
        for record in range(element.count):
            self._walk(element, record, None)

    def _walk(self, element: _Element, record: int, out: bytearray | None) -> None:
        data = self.data
        for p in element.properties:
            if not p.is_list:
                size = np.dtype(p.kind).itemsize
                if self.pos + size > len(data):
                    self.truncated(element, record)
                if out is not None:
                    out += data[self.pos : self.pos + size]
                self.pos += size
                continue
            length_type = np.dtype(self.order + p.length_kind)
            if self.pos + length_type.itemsize > len(data):
                self.truncated(element, record)
            length = int(np.frombuffer(data, length_type, 1, self.pos)[0])
            if length < 0:
                raise PlyError(f"{self.path}: element '{element.name}' record {record}: "
                               f"negative length of list '{p.name}'")
            self.pos += length_type.itemsize
            size = length * np.dtype(p.kind).itemsize
            if self.pos + size > len(data):
                self.truncated(element, record)
            self.pos += size

    def vertices(self, vertex: _Element) -> np.ndarray:
        """The vertex records' scalar properties, as a structured array p0, p1, ..."""
        dtype = _record_dtype(vertex.scalars(), self.order)
        if not vertex.has_lists:
            size = vertex.count * dtype.itemsize
            if size > len(self.data) - self.pos:
                raise PlyError(f"{self.path}: truncated binary data: expected {size} bytes for "
                               f"{vertex.count} vertices, found {len(self.data) - self.pos}")
            return np.frombuffer(self.data, dtype, vertex.count, self.pos)
        # Every record holds at least its list lengths: check before allocating.
        least = sum(np.dtype(p.length_kind if p.is_list else p.kind).itemsize
                    for p in vertex.properties)
        if vertex.count * least > len(self.data) - self.pos:
            self.truncated(vertex, (len(self.data) - self.pos) // max(least, 1))
        packed = bytearray()
        for record in range(vertex.count):
            self._walk(vertex, record, packed)
        return np.frombuffer(bytes(packed), dtype, vertex.count)


# ---------------------------------------------------------------------------------------------
# ASCII


def _ascii_vertices(path: str, elements: list, vertex_index: int, data: bytes) -> list:
    """The vertex element's scalar columns as arrays of their types, from ascii data."""
    tokens = data.split()
    pos = 0

    def need(count: int, element: _Element, record: int):
        if pos + count > len(tokens):
            raise PlyError(f"{path}: ascii data ends after {record} of {element.count} "
                           f"'{element.name}' records")

    def list_length(token: bytes, element: _Element, p: _Property, record: int) -> int:
        try:
            length = int(token)
        except ValueError:
            length = -1
        if length < 0:
            raise PlyError(f"{path}: element '{element.name}' record {record}: length "
                           f"'{token.decode('latin-1')}' of list '{p.name}' is not a "
                           "non-negative integer")
        return length

    def record_scalars(element: _Element, record: int) -> list:
        """Walks one record of a list-bearing element: its scalar tokens, the lists passed over."""
        nonlocal pos
        scalars = []
        for p in element.properties:
            need(1, element, record)
            if p.is_list:
                length = list_length(tokens[pos], element, p, record)
                need(1 + length, element, record)
                pos += 1 + length
            else:
                scalars.append(tokens[pos])
                pos += 1
        return scalars

    for element in elements[:vertex_index]:
        if not element.properties:
            continue
        if not element.has_lists:
            need(element.count * len(element.properties), element, 0)
            pos += element.count * len(element.properties)
            continue
        for record in range(element.count):
            record_scalars(element, record)

    vertex = elements[vertex_index]
    scalars = vertex.scalars()
    if not vertex.has_lists:
        need(vertex.count * len(scalars), vertex, 0)
        table = np.array(tokens[pos : pos + vertex.count * len(scalars)], dtype=bytes)
        table = table.reshape(vertex.count, len(scalars))
    else:
        rows = [record_scalars(vertex, record) for record in range(vertex.count)]
        table = np.array(rows, dtype=bytes).reshape(vertex.count, len(scalars))
    columns = []
    for i, p in enumerate(scalars):
        text = table[:, i]
        try:
            values = ascii_values(text, p.kind)
        except ValueError:
            raise PlyError(f"{path}: a value of vertex property '{p.name}' is not a valid "
                           f"{p.kind}") from None
        columns.append(values)
    return columns


# ---------------------------------------------------------------------------------------------


def _labels(path: str, values: np.ndarray) -> np.ndarray:
    def fail(i, value):
        raise PlyError(f"{path}: property 'label' of vertex {i}: value {value} is not a label "
                       "(an integer in 0..4294967295)")

    return checked_labels(values, fail)


def read(path) -> PointCloud:
    """Reads a PLY file's vertices as a pcd.PointCloud; PlyError (a ValueError) says what is
    wrong with a malformed one."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise PlyError(f"{path}: cannot read: {e.strerror}") from None
    fmt, elements, data_offset = _parse_header(path, raw)
    vertex_index = next((i for i, e in enumerate(elements) if e.name == "vertex"), None)
    if vertex_index is None:
        raise PlyError(f"{path}: no 'vertex' element")
    vertex = elements[vertex_index]
    if vertex.count > 0xFFFFFFFF:
        raise PlyError(f"{path}: vertex count {vertex.count} exceeds 4294967295")
    _check_vertex(path, vertex)
    data = raw[data_offset:]
    scalars = vertex.scalars()
    if fmt == "ascii":
        columns = _ascii_vertices(path, elements, vertex_index, data)
    else:
        walker = _BinaryWalker(path, data, _FORMATS[fmt])
        for element in elements[:vertex_index]:
            walker.skip(element)
        records = walker.vertices(vertex)
        native = [np.dtype(p.kind) for p in scalars]
        columns = [records[f"p{i}"].astype(native[i]) for i in range(len(scalars))]
    by_name = dict(zip((p.name for p in scalars), columns))
    order = [p.name for p in scalars]
    n = vertex.count

    def take(name):
        order.remove(name)
        return by_name.pop(name)

    def floats(names):
        wide = any(by_name[a].dtype == np.float64 for a in names)
        return np.stack([take(a) for a in names], axis=1).astype(
            np.float64 if wide else np.float32).reshape(n, 3)

    cloud = PointCloud(xyz=floats("xyz"), width=n, height=1)
    for names in _NORMALS:
        if all(a in by_name for a in names):
            cloud.normals = floats(names)
            break
    if "curvature" in by_name:
        cloud.curvature = take("curvature")
    if "label" in by_name:
        cloud.label = _labels(path, take("label"))
    if all(c in by_name for c in ("red", "green", "blue")):
        rgb = np.full(n, 0 if "alpha" in by_name else 0xFF000000, dtype=np.uint32)
        for name, shift in _COLOURS:
            if name in by_name:
                rgb |= take(name).astype(np.uint32) << np.uint32(shift)
        cloud.rgb = rgb
    # The rest: runs base_0 .. base_k (k >= 1) are one (N, k + 1) field, as written.
    names = set(p.name for p in vertex.properties)
    i = 0
    while i < len(order):
        name = order[i]
        run = 1
        match = re.fullmatch(r"(.+)_0", name)
        if match and match.group(1) not in names:
            base = match.group(1)
            while i + run < len(order) and order[i + run] == f"{base}_{run}":
                run += 1
        if run >= 2:
            cloud.fields[base] = np.stack([by_name[order[i + e]] for e in range(run)], axis=1)
        else:
            cloud.fields[name] = by_name[name]
        i += run
    cloud.classes = labeled.classes(path, raw, ply=True)
    return cloud
