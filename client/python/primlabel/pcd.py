"""PCD v0.7 files to and from numpy, read as core/geometry's reader does (pcd_io.cpp): DATA ascii,
binary and binary_compressed; written as ascii, binary or binary_compressed (LZF through liblzf).

    cloud = primlabel.pcd.read("scan.pcd")
    cloud.xyz          # (N, 3); organised clouds keep their NaN pixels, width and height
    cloud.grid(cloud.xyz)  # (height, width, 3)
    primlabel.pcd.write("out.pcd", cloud, encoding="binary")

Field mapping: x y z -> xyz; normal_x normal_y normal_z -> normals; curvature; label -> label
(uint32; must be integers in 0..2^32-1); rgb / rgba -> rgb (uint32, the 4 bytes bit for bit, as
PCL packs 0xAARRGGBB); every other field -> fields[name], (N,) for COUNT 1 and (N, COUNT)
otherwise, in its stored type; COUNT 1 columns name_0 .. name_k beside a field `name` of COUNT
k + 1 are its copies for one-value-per-field readers (Open3D), which write() adds and read() folds
back. "_" padding fields are skipped. Every size the header declares is
checked against the bytes really in the file before anything proportional to it is allocated.
"""

from __future__ import annotations

import os
import struct
import tempfile
from dataclasses import dataclass, field

import numpy as np

from . import labeled, lzf

_IDENTITY_VIEWPOINT = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
_SINGLE_VALUE = ("x", "y", "z", "normal_x", "normal_y", "normal_z", "curvature", "label", "rgb",
                 "rgba")
_NORMALS = ("normal_x", "normal_y", "normal_z")
# No LZF stream expands more than 88 times (a 3-byte back-reference gives at most 264 bytes).
_MAX_LZF_EXPANSION = 88


class PcdError(ValueError):
    """A file that cannot be read or a cloud that cannot be written; the message starts with
    the path."""


@dataclass
class PointCloud:
    xyz: np.ndarray  # (N, 3) float32 (float64 when the file stores x, y or z as F 8)
    normals: np.ndarray | None = None  # (N, 3)
    curvature: np.ndarray | None = None  # (N,)
    label: np.ndarray | None = None  # (N,) uint32
    rgb: np.ndarray | None = None  # (N,) uint32 packed 0xAARRGGBB
    fields: dict = field(default_factory=dict)  # name -> (N,) or (N, COUNT), stored dtype
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


@dataclass
class _Field:
    name: str
    kind: str  # F, I or U
    size: int  # bytes of one value
    count: int

    @property
    def padding(self) -> bool:
        return self.name == "_"

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(f"<{ {'F': 'f', 'I': 'i', 'U': 'u'}[self.kind] }{self.size}")

    @property
    def bytes(self) -> int:
        return self.size * self.count


@dataclass
class _Header:
    fields: list
    width: int
    height: int
    points: int
    viewpoint: tuple
    encoding: str
    data_offset: int


# ---------------------------------------------------------------------------------------------
# Reading


def _parse_header(path: str, raw: bytes) -> _Header:
    def fail(line: int, message: str):
        raise PcdError(f"{path}: header line {line}: {message}")

    entries: dict = {}
    pos = 0
    line_number = 0
    while pos < len(raw):
        end = raw.find(b"\n", pos)
        end = len(raw) if end < 0 else end
        text = raw[pos:end].decode("latin-1")
        pos = end + 1
        line_number += 1
        tokens = text.split()
        if not tokens or tokens[0].startswith("#"):
            continue
        keyword, values = tokens[0], tokens[1:]
        if line_number == 1 and tokens == ["ply"]:
            raise PcdError(f"{path}: a PLY file, not a PCD file: read it with primlabel.ply.read "
                           "(or primlabel.read, by the extension)")
        if keyword == "COLUMNS":
            keyword = "FIELDS"
        if keyword not in ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT",
                           "POINTS", "VIEWPOINT", "DATA"):
            if keyword[0] in "0123456789+-.":
                fail(line_number, f"data value '{keyword}' before any DATA line")
            fail(line_number, f"unknown header keyword '{keyword}'")
        if keyword in entries:
            fail(line_number, f"duplicate {keyword} line (first on line {entries[keyword][1]})")
        entries[keyword] = (values, line_number)
        if keyword == "DATA":
            return _build_header(path, entries, min(pos, len(raw)), fail)
    if not raw:
        raise PcdError(f"{path}: empty file, not a PCD file")
    raise PcdError(f"{path}: header: missing DATA line (the header runs to the end of the file)")


def _integer(text: str, what: str, line: int, fail, low: int = 0, high: int = 0xFFFFFFFF) -> int:
    try:
        value = int(text, 10)
    except ValueError:
        value = None
    if value is None or not low <= value <= high:
        fail(line, f"{what} must be an integer in {low}..{high}, got '{text}'")
    return value


def _build_header(path: str, entries: dict, data_offset: int, fail) -> _Header:
    if "VERSION" in entries:
        values, line = entries["VERSION"]
        if values not in (["0.7"], [".7"], ["0.6"], [".6"], ["0.5"], [".5"]):
            fail(line, f"unsupported VERSION {' '.join(values)!r} (0.5 to 0.7 are read)")
    if "FIELDS" not in entries or not entries["FIELDS"][0]:
        raise PcdError(f"{path}: header: missing FIELDS line")
    names, fields_line = entries["FIELDS"]
    n = len(names)
    for keyword in ("SIZE", "TYPE", "COUNT"):
        if keyword in entries and len(entries[keyword][0]) != n:
            fail(entries[keyword][1],
                 f"{keyword} has {len(entries[keyword][0])} entries but FIELDS has {n}")
    sizes = entries.get("SIZE", (["4"] * n, fields_line))
    types = entries.get("TYPE", (["F"] * n, fields_line))
    counts = entries.get("COUNT", (["1"] * n, fields_line))
    fields = []
    for i, name in enumerate(names):
        size = sizes[0][i]
        if size not in ("1", "2", "4", "8"):
            fail(sizes[1], f"SIZE of field '{name}' is '{size}', expected 1, 2, 4 or 8")
        kind = types[0][i]
        if kind not in ("F", "I", "U"):
            fail(types[1], f"TYPE of field '{name}' is '{kind}', expected F, I or U")
        if kind == "F" and size not in ("4", "8"):
            fail(types[1], f"field '{name}' has TYPE F with SIZE {size} (F needs SIZE 4 or 8)")
        count = _integer(counts[0][i], f"COUNT of field '{name}'", counts[1], fail, low=1)
        fields.append(_Field(name, kind, int(size), count))
    seen = set()
    for f in fields:
        if f.padding:
            continue
        if f.name in seen:
            fail(fields_line, f"field '{f.name}' is listed twice")
        seen.add(f.name)
        if f.name in _SINGLE_VALUE and f.count != 1:
            fail(counts[1], f"field '{f.name}' must have COUNT 1, got {f.count}")
        if f.name in ("rgb", "rgba") and f.size != 4:
            fail(sizes[1], f"field '{f.name}' is a packed colour and needs SIZE 4, got {f.size}")
    for axis in "xyz":
        if axis not in seen:
            fail(fields_line, f"missing field '{axis}' (x, y and z are required)")
    if "rgb" in seen and "rgba" in seen:
        fail(fields_line, "both 'rgb' and 'rgba' are present")

    def dimension(keyword):
        if keyword not in entries:
            return None, 0
        values, line = entries[keyword]
        if len(values) != 1:
            fail(line, f"{keyword} needs exactly one value")
        high = 2**64 - 1 if keyword == "POINTS" else 0xFFFFFFFF
        return _integer(values[0], keyword, line, fail, high=high), line

    width, width_line = dimension("WIDTH")
    height, height_line = dimension("HEIGHT")
    points, points_line = dimension("POINTS")
    if points is None and width is None:
        raise PcdError(f"{path}: header: missing POINTS and WIDTH lines")
    if height is None:
        height = 1
    if width is None:
        if height != 1:
            fail(height_line, "HEIGHT given without WIDTH")
        width, width_line = points, points_line
    if points is None:
        points = width * height
    if width * height != points:
        fail(points_line, f"WIDTH {width} x HEIGHT {height} = {width * height} does not match "
                          f"POINTS {points}")
    if points == 0:
        height = max(height, 1)

    viewpoint = _IDENTITY_VIEWPOINT
    if "VIEWPOINT" in entries:
        values, line = entries["VIEWPOINT"]
        if len(values) != 7:
            fail(line, f"VIEWPOINT needs 7 values (tx ty tz qw qx qy qz), got {len(values)}")
        try:
            viewpoint = tuple(float(v) for v in values)
        except ValueError:
            fail(line, f"VIEWPOINT values {' '.join(values)!r} are not numbers")

    values, line = entries["DATA"]
    if len(values) != 1 or values[0] not in ("ascii", "binary", "binary_compressed"):
        fail(line, f"unknown DATA kind {' '.join(values)!r} "
                   "(expected ascii, binary or binary_compressed)")
    return _Header(fields, width, height, points, viewpoint, values[0], data_offset)


def _ascii_columns(path: str, header: _Header, data: bytes) -> list:
    per_point = sum(f.count for f in header.fields)
    lines = [line for line in data.split(b"\n") if line.strip()]
    if len(lines) != header.points:
        raise PcdError(f"{path}: ascii data has {len(lines)} points, POINTS declares "
                       f"{header.points}")
    tokens = b" ".join(lines).split()
    if len(tokens) != header.points * per_point:
        widths = [len(line.split()) for line in lines]
        bad = next(i for i, w in enumerate(widths) if w != per_point)
        raise PcdError(f"{path}: expected {per_point} values for point {bad}, found {widths[bad]}")
    table = np.array(tokens, dtype=bytes).reshape(header.points, per_point)
    columns, start = [], 0
    for f in header.fields:
        text = table[:, start : start + f.count]
        start += f.count
        if f.padding:
            columns.append(None)
            continue
        try:
            values = ascii_values(text, f.dtype)
        except ValueError:
            raise PcdError(f"{path}: a value of field '{f.name}' is not a valid "
                           f"{f.kind} {f.size} number") from None
        columns.append(values)
    return columns


def ascii_values(text: np.ndarray, dtype) -> np.ndarray:
    """Byte-string tokens as numbers of `dtype`; ValueError for a token that is not one, or an
    integer out of the type's range (read through a wide integer, so it is caught, not wrapped).
    The PCD and the PLY readers' ascii bodies."""
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return text.astype(dtype)
    wide = text.astype(np.int64 if dtype.kind == "i" else np.uint64)
    info = np.iinfo(dtype)
    if wide.size and (wide.min() < info.min or wide.max() > info.max):
        raise ValueError("out of range")
    return wide.astype(dtype)


def _binary_columns(path: str, header: _Header, data: bytes) -> list:
    record = sum(f.bytes for f in header.fields)
    needed = header.points * record
    if needed > len(data):
        raise PcdError(f"{path}: truncated binary data: expected {needed} bytes for "
                       f"{header.points} points, found {len(data)}")
    columns, offset = [], 0
    for f in header.fields:
        if f.padding:
            columns.append(None)
        else:
            layout = np.dtype({"names": ["v"], "formats": [(f.dtype, (f.count,))],
                               "offsets": [offset], "itemsize": record})
            columns.append(np.frombuffer(data, dtype=layout, count=header.points)["v"].copy())
        offset += f.bytes
    return columns


def _compressed_columns(path: str, header: _Header, data: bytes) -> list:
    plane_bytes = sum(f.bytes for f in header.fields if not f.padding)
    if len(data) < 8:
        if header.points == 0:
            return [None if f.padding else np.zeros((0, f.count), f.dtype) for f in header.fields]
        raise PcdError(f"{path}: truncated binary_compressed data: expected an 8-byte size "
                       f"header, found {len(data)} bytes")
    compressed_size, uncompressed_size = struct.unpack_from("<II", data)
    if header.points * plane_bytes != uncompressed_size:
        raise PcdError(f"{path}: binary_compressed header says {uncompressed_size} uncompressed "
                       f"bytes, but {header.points} points x {plane_bytes} bytes need "
                       f"{header.points * plane_bytes}")
    if compressed_size > len(data) - 8:
        raise PcdError(f"{path}: compressed size {compressed_size} is larger than the "
                       f"{len(data) - 8} bytes remaining in the file")
    if uncompressed_size > _MAX_LZF_EXPANSION * compressed_size:
        raise PcdError(f"{path}: {compressed_size} compressed bytes cannot hold "
                       f"{uncompressed_size} bytes")
    try:
        planes = lzf.decompress(data[8 : 8 + compressed_size], uncompressed_size)
    except lzf.LzfError as e:
        raise PcdError(f"{path}: corrupt binary_compressed data: {e}") from None
    columns, offset = [], 0
    for f in header.fields:
        if f.padding:
            columns.append(None)
            continue
        values = np.frombuffer(planes, dtype=f.dtype, count=header.points * f.count,
                               offset=offset)
        columns.append(values.reshape(header.points, f.count).copy())
        offset += header.points * f.bytes
    return columns


def read(path: str) -> PointCloud:
    """Reads a PCD file; PcdError (a ValueError) says what is wrong with a malformed one. PLY
    files: primlabel.ply.read, or primlabel.read for either by the extension."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise PcdError(f"{path}: cannot read: {e.strerror}") from None
    header = _parse_header(path, raw)
    data = raw[header.data_offset :]
    if header.encoding == "ascii":
        columns = _ascii_columns(path, header, data)
    elif header.encoding == "binary":
        columns = _binary_columns(path, header, data)
    else:
        columns = _compressed_columns(path, header, data)
    by_name = {f.name: c for f, c in zip(header.fields, columns) if not f.padding}
    kinds = {f.name: f for f in header.fields}

    def take(name):
        return by_name.pop(name)[:, 0]

    def floats(names):
        wide = any(kinds[n].dtype == np.float64 for n in names)
        return np.stack([take(n) for n in names], axis=1).astype(
            np.float64 if wide else np.float32)

    cloud = PointCloud(xyz=floats("xyz"), width=header.width, height=header.height,
                       viewpoint=header.viewpoint)
    if all(n in by_name for n in _NORMALS):
        cloud.normals = floats(_NORMALS)
    if "curvature" in by_name:
        cloud.curvature = take("curvature")
    if "label" in by_name:
        cloud.label = _labels(path, take("label"))
    for colour in ("rgba", "rgb"):
        if colour in by_name:
            cloud.rgb = take(colour).view(np.uint32) if len(cloud.xyz) else np.zeros(0, np.uint32)
    for name, values in by_name.items():
        if _is_scalar_copy(name, kinds):
            continue
        cloud.fields[name] = values[:, 0] if kinds[name].count == 1 else values
    cloud.classes = labeled.classes(path, raw)
    return cloud


def _is_scalar_copy(name: str, kinds: dict) -> bool:
    """name_e of COUNT 1 beside a field `name` of more than e values: one of the columns a
    multi-value field is also written as (for readers such as Open3D that take one value per
    field), read back as part of that field."""
    base, _, element = name.rpartition("_")
    if kinds[name].count != 1 or not base or not element.isdigit():
        return False
    return base in kinds and kinds[base].count > int(element)


def checked_labels(values: np.ndarray, fail) -> np.ndarray:
    """`values` as uint32 labels; fail(i, value) raises for the first one that is not an integer
    in 0..4294967295 (the PCD and the PLY readers word it their way)."""
    with np.errstate(invalid="ignore"):
        representable = (values >= 0) & (values <= 0xFFFFFFFF)
        if values.dtype.kind == "f":
            representable &= np.trunc(values) == values
    if not representable.all():
        i = int(np.argmin(representable))
        fail(i, values[i])
    return values.astype(np.uint32)


def _labels(path: str, values: np.ndarray) -> np.ndarray:
    def fail(i, value):
        raise PcdError(f"{path}: field 'label' of point {i}: value {value} is not a label "
                       "(an integer in 0..4294967295)")

    return checked_labels(values, fail)


# ---------------------------------------------------------------------------------------------
# Writing


def _pcd_type(dtype: np.dtype) -> tuple[str, int]:
    if dtype.kind == "f" and dtype.itemsize in (4, 8):
        return "F", dtype.itemsize
    if dtype.kind in "iu" and dtype.itemsize in (1, 2, 4, 8):
        return dtype.kind.upper(), dtype.itemsize
    if dtype.kind == "b":
        return "U", 1
    raise TypeError(f"dtype {dtype} has no PCD type")


def _output_columns(path: str, cloud: PointCloud) -> list:
    """(name, (N, count) array) in the order core/geometry writes them."""
    n = len(cloud.xyz)

    def per_point(values, what, columns=None):
        array = np.asarray(values)
        if array.ndim == 1:
            array = array[:, None]
        if array.ndim != 2 or array.shape[0] != n or (columns and array.shape[1] != columns):
            want = f"({n}, {columns})" if columns else f"({n},) or ({n}, COUNT)"
            raise PcdError(f"{path}: {what} has shape {np.shape(values)}, expected {want}")
        try:
            _pcd_type(array.dtype)
        except TypeError as e:
            raise PcdError(f"{path}: {what}: {e}") from None
        return array

    xyz = per_point(cloud.xyz, "xyz", 3)
    if xyz.dtype.kind != "f":
        xyz = xyz.astype(np.float32)
    out = [(axis, xyz[:, i : i + 1]) for i, axis in enumerate("xyz")]
    if cloud.normals is not None:
        normals = per_point(cloud.normals, "normals", 3)
        out += [(name, normals[:, i : i + 1]) for i, name in enumerate(_NORMALS)]
    if cloud.curvature is not None:
        out.append(("curvature", per_point(cloud.curvature, "curvature", 1)))
    if cloud.label is not None:
        out.append(("label", per_point(cloud.label, "label", 1).astype(np.uint32)))
    if cloud.rgb is not None:
        out.append(("rgba", per_point(cloud.rgb, "rgb", 1).astype(np.uint32)))
    for name, values in cloud.fields.items():
        if not name or any(c.isspace() for c in name) or name == "_":
            raise PcdError(f"{path}: field name {name!r} cannot be written")
        out.append((name, per_point(values, f"field '{name}'")))
    names = [name for name, _ in out]
    for name in names:
        if names.count(name) > 1:
            raise PcdError(f"{path}: field '{name}' would be written twice")
    # A multi-value field (fpfh, COUNT 33) also as columns fpfh_0 .. fpfh_32, as core/geometry
    # writes it: Open3D keeps only the first value of a COUNT > 1 field.
    for name, values in list(out):
        copies = [f"{name}_{e}" for e in range(values.shape[1])]
        if values.shape[1] > 1 and not any(c in names for c in copies):
            out += [(c, values[:, e : e + 1]) for e, c in enumerate(copies)]
    return out


def _format_column(values: np.ndarray) -> np.ndarray:
    if values.dtype.kind == "f":
        text = np.char.mod("%.17g" if values.dtype.itemsize == 8 else "%.9g", values)
        return np.where(np.isnan(values), "nan", text)
    return np.char.mod("%d", values.astype(np.int64 if values.dtype.kind == "i" else np.uint64))


def write(path: str, cloud: PointCloud, encoding: str = "binary") -> None:
    """Writes `cloud` as PCD v0.7, DATA ascii, binary or binary_compressed (little-endian; LZF
    through liblzf), atomically (a temporary file beside `path` renamed over it). Floats keep
    their width (F 4 / F 8)."""
    path = os.fspath(path)
    if encoding not in ("ascii", "binary", "binary_compressed"):
        raise PcdError(f"{path}: encoding must be 'ascii', 'binary' or 'binary_compressed', "
                       f"got {encoding!r}")
    n = len(cloud.xyz)
    width = n if cloud.width is None else int(cloud.width)
    if width * int(cloud.height) != n:
        raise PcdError(f"{path}: width {width} x height {cloud.height} is not {n} points")
    viewpoint = tuple(float(v) for v in cloud.viewpoint)
    if len(viewpoint) != 7:
        raise PcdError(f"{path}: viewpoint needs 7 values (tx ty tz qw qx qy qz)")
    columns = _output_columns(path, cloud)
    types = [_pcd_type(values.dtype) for _, values in columns]
    lines = [
        "# .PCD v0.7 - Point Cloud Data file format",
        "VERSION 0.7",
        "FIELDS " + " ".join(name for name, _ in columns),
        "SIZE " + " ".join(str(size) for _, size in types),
        "TYPE " + " ".join(kind for kind, _ in types),
        "COUNT " + " ".join(str(values.shape[1]) for _, values in columns),
        f"WIDTH {width}",
        f"HEIGHT {int(cloud.height)}",
        "VIEWPOINT " + " ".join(f"{v:.9g}" for v in viewpoint),
        f"POINTS {n}",
        f"DATA {encoding}",
    ]
    body = "\n".join(lines).encode() + b"\n"
    if encoding == "ascii":
        if n:
            text = np.concatenate([_format_column(values) for _, values in columns], axis=1)
            body += ("\n".join(" ".join(row) for row in text.tolist()) + "\n").encode()
    elif encoding == "binary_compressed":
        body += _compressed_body(path, columns)
    else:
        layout = np.dtype({
            "names": [f"f{i}" for i in range(len(columns))],
            "formats": [(values.dtype.newbyteorder("<"), (values.shape[1],))
                        for _, values in columns],
        })
        records = np.empty(n, dtype=layout)
        for i, (_, values) in enumerate(columns):
            records[f"f{i}"] = values
        body += records.tobytes()
    _write_atomically(path, body)


def _compressed_body(path: str, columns: list) -> bytes:
    """PCD's binary_compressed data: the uint32 compressed and uncompressed sizes, then one LZF
    block of the fields one after another (each field's values for all points together), the
    layout PCL writes and core/geometry and _compressed_columns read."""
    planes = b"".join(np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("<")).tobytes()
                      for _, values in columns)
    try:
        compressed = lzf.compress(planes)
    except lzf.LzfError as e:
        raise PcdError(f"{path}: cannot write binary_compressed: {e}") from None
    return struct.pack("<II", len(compressed), len(planes)) + compressed


def _write_atomically(path: str, data: bytes) -> None:
    directory = os.path.dirname(os.path.abspath(path))
    try:
        fd, temporary = tempfile.mkstemp(prefix=".pcd-", dir=directory)
    except OSError as e:
        raise PcdError(f"{path}: cannot write: {e.strerror}") from None
    try:
        os.fchmod(fd, 0o644)  # mkstemp's 0600 would hide the file from other users
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temporary, path)
    except OSError as e:
        os.unlink(temporary)
        raise PcdError(f"{path}: cannot write: {e.strerror}") from None
