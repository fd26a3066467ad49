"""primlabel.ply reads the PLY the C++ CLI writes (labels, prob_<class> and fpfh fields) value for
value, in ascii, binary_little_endian and binary_big_endian; primlabel.read picks the reader by
the extension; and malformed or unknown files fail with a message naming the problem."""

from __future__ import annotations

import numpy as np
import pytest

import primlabel
from conftest import binary, run


def ply_bytes(encoding: str, columns: list, before: bytes = b"", after: bytes = b"",
              header_extra: str = "") -> bytes:
    """A PLY of the vertex columns [(name, ply type, (N,) array)], with raw elements around."""
    dtypes = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4",
              "uint": "u4", "float": "f4", "double": "f8"}
    n = len(columns[0][2])
    header = f"ply\nformat {encoding} 1.0\ncomment made by test_ply\n{header_extra}"
    header += f"element vertex {n}\n"
    header += "".join(f"property {kind} {name}\n" for name, kind, _ in columns)
    header += "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    if encoding == "ascii":
        rows = [" ".join(repr(float(v)) if kind in ("float", "double") else str(int(v))
                         for _, kind, values in columns for v in [values[i]])
                for i in range(n)]
        body = before + ("\n".join(rows) + "\n").encode() + after
    else:
        order = "<" if encoding == "binary_little_endian" else ">"
        records = np.empty(n, dtype=[(name, order + dtypes[kind]) for name, kind, _ in columns])
        for name, _, values in columns:
            records[name] = values
        body = before + records.tobytes() + after
    return header.encode() + body


def example_columns(n: int = 5):
    rng = np.random.default_rng(4)
    xyz = rng.normal(size=(n, 3)).astype(np.float32)
    return xyz, [
        ("x", "float", xyz[:, 0]), ("y", "float", xyz[:, 1]), ("z", "float", xyz[:, 2]),
        ("nx", "float", np.ones(n)), ("ny", "float", np.zeros(n)), ("nz", "float", np.zeros(n)),
        ("label", "int", np.arange(n) % 3), ("red", "uchar", np.full(n, 255)),
        ("green", "uchar", np.arange(n)), ("blue", "uchar", np.full(n, 7)),
        ("prob_plane", "float", np.linspace(0, 1, n)), ("intensity", "ushort", np.arange(n) * 300),
        ("fpfh_0", "float", np.arange(n)), ("fpfh_1", "float", np.arange(n) + 0.5),
        ("fpfh_2", "float", np.arange(n) + 0.25), ("height", "double", np.arange(n) / 3),
    ]


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_every_encoding_reads_the_same_cloud(tmp_path, encoding):
    xyz, columns = example_columns()
    face = b"3 0 1 2\n" if encoding == "ascii" else (
        b"\x03" + np.array([0, 1, 2], "<i4" if "little" in encoding else ">i4").tobytes())
    path = tmp_path / "cloud.ply"
    path.write_bytes(ply_bytes(encoding, columns, after=face))
    cloud = primlabel.ply.read(path)
    np.testing.assert_array_equal(cloud.xyz, xyz)
    assert cloud.xyz.dtype == np.float32 and (cloud.width, cloud.height) == (5, 1)
    np.testing.assert_array_equal(cloud.normals, np.tile([1, 0, 0], (5, 1)))
    assert cloud.label.dtype == np.uint32
    np.testing.assert_array_equal(cloud.label, [0, 1, 2, 0, 1])
    # Packed as PCL does, 0xAARRGGBB; opaque without alpha.
    np.testing.assert_array_equal(cloud.rgb, 0xFFFF0007 | (np.arange(5, dtype=np.uint32) << 8))
    assert sorted(cloud.fields) == ["fpfh", "height", "intensity", "prob_plane"]
    np.testing.assert_array_equal(cloud.fields["fpfh"],
                                  np.arange(5)[:, None] + np.array([0, 0.5, 0.25]))
    assert cloud.fields["intensity"].dtype == np.float32  # the C++ reader's FloatField
    np.testing.assert_array_equal(cloud.fields["intensity"], np.arange(5) * 300)
    np.testing.assert_array_equal(cloud.fields["height"], np.float32(np.arange(5) / 3))
    assert cloud.viewpoint == primlabel.pcd.PointCloud(xyz=xyz).viewpoint  # PLY has none
    # By the extension, in any case.
    upper = tmp_path / "CLOUD.PLY"
    upper.write_bytes(path.read_bytes())
    np.testing.assert_array_equal(primlabel.read(str(upper)).label, cloud.label)


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
def test_written_ply_reads_back(tmp_path, encoding):
    rng = np.random.default_rng(6)
    cloud = primlabel.pcd.PointCloud(
        xyz=rng.normal(size=(4, 3)).astype(np.float32), label=np.arange(4, dtype=np.uint32),
        rgb=np.array([0xFF102030, 0xFF000000, 0x80FFFFFF, 0xFFABCDEF], np.uint32),
        fields={"fpfh": rng.uniform(size=(4, 3)).astype(np.float32),
                "prob_plane": np.linspace(0, 1, 4, dtype=np.float32)})
    path = tmp_path / "written.ply"
    primlabel.ply.write(path, cloud, encoding=encoding)
    assert f"format {encoding} 1.0".encode() in path.read_bytes()[:200]
    back = primlabel.ply.read(path)
    for name in ("xyz", "label", "rgb"):
        np.testing.assert_array_equal(getattr(back, name), getattr(cloud, name), err_msg=name)
    assert back.fields.keys() == cloud.fields.keys()
    for name, values in cloud.fields.items():
        np.testing.assert_array_equal(back.fields[name], values, err_msg=name)
    with pytest.raises(primlabel.ply.PlyError, match="encoding must be"):
        primlabel.ply.write(path, cloud, encoding="binary_big_endian")


def test_elements_before_the_vertex_are_skipped(tmp_path):
    xyz, columns = example_columns(3)
    path = tmp_path / "lists.ply"
    extra = "element camera 2\nproperty float f\nproperty list uchar int ids\n"
    # Binary, little-endian: two camera records with lists of 2 and 0 ints.
    before = (np.array([1.5], "<f4").tobytes() + b"\x02" + np.array([4, 5], "<i4").tobytes()
              + np.array([2.5], "<f4").tobytes() + b"\x00")
    path.write_bytes(ply_bytes("binary_little_endian", columns[:3], before=before,
                               header_extra=extra))
    np.testing.assert_array_equal(primlabel.ply.read(path).xyz, xyz)
    path.write_bytes(ply_bytes("ascii", columns[:3], before=b"1.5 2 4 5\n2.5 0\n",
                               header_extra=extra))
    np.testing.assert_array_equal(primlabel.ply.read(path).xyz, xyz)


@pytest.mark.parametrize("content,message", [
    (b"", "empty file"),
    (b"VERSION 0.7\n", "not a PLY file"),
    (b"ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n",
     "unsupported format 'binary_middle_endian'"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     b"end_header\n1 2\n", "lacks property x, y or z"),
    (b"ply\nformat ascii 1.0\nelement face 0\nend_header\n", "no 'vertex' element"),
    (b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
     b"property float z\nend_header\n1 2 3\n", "ascii data ends after 1 of 2 'vertex' records"),
    (b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
     b"property float y\nproperty float z\nend_header\n" + b"\0" * 12,
     "truncated binary data: expected 12000000000 bytes"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     b"property float z\nproperty float label\nend_header\n1 2 3 0.5\n", "is not a label"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
     b"property float z\nproperty uchar u\nend_header\n1 2 3 256\n",
     "vertex 0: property 'u': '256' is not a valid uchar"),
    (b"ply\nformat ascii 1.0\nproperty float x\n", "property before any element"),
    (b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n", "missing end_header"),
])
def test_malformed_files_say_what_is_wrong(tmp_path, content, message):
    path = tmp_path / "bad.ply"
    path.write_bytes(content)
    with pytest.raises(primlabel.ply.PlyError, match=message) as error:
        primlabel.ply.read(path)
    assert str(error.value).startswith(str(path))
    assert isinstance(error.value, ValueError)


def test_pcd_read_and_the_generic_read_name_the_format(tmp_path):
    _, columns = example_columns(2)
    ply = tmp_path / "cloud.ply"
    ply.write_bytes(ply_bytes("ascii", columns[:3]))
    with pytest.raises(primlabel.pcd.PcdError, match="a PLY file, not a PCD file"):
        primlabel.pcd.read(ply)
    for name in ("cloud.xyz", "cloud"):
        (tmp_path / name).write_bytes(b"1 2 3\n")
        with pytest.raises(primlabel.UnsupportedFormat, match="unknown point cloud format") as e:
            primlabel.read(tmp_path / name)
        assert isinstance(e.value, ValueError)


def reencoded(data: bytes, encoding: str, n: int) -> bytes:
    """A binary_little_endian PLY of n float32/int32/uint32 vertex properties (what the CLI
    writes), rewritten as `encoding`."""
    head, body = data.split(b"end_header\n", 1)
    lines = head.decode().splitlines()
    kinds = [line.split()[1] for line in lines if line.startswith("property ")]
    codes = {"float": "f4", "int": "i4", "uint": "u4", "uchar": "u1"}
    layout = np.dtype([(f"p{i}", "<" + codes[k]) for i, k in enumerate(kinds)])
    records = np.frombuffer(body, layout, n)
    head = head.replace(b"format binary_little_endian", b"format " + encoding.encode())
    if encoding == "binary_big_endian":
        return head + b"end_header\n" + records.astype(layout.newbyteorder(">")).tobytes()
    rows = [" ".join(repr(float(v)) if k == "float" else str(int(v))
                     for v, k in zip(record, kinds)) for record in records.tolist()]
    return head + b"end_header\n" + ("\n".join(rows) + "\n").encode()


def test_the_cli_s_ply_reads_as_its_pcd(server, scan, tmp_path):
    # The CLI writes the same labeled cloud as PCD and as PLY (binary_little_endian): the PLY
    # reads back to the same labels, probabilities and descriptors.
    cli = binary("primlabel")
    for out in ("labeled.pcd", "labeled.ply"):
        run(cli, "--server", server.address, "label", scan, "-o", tmp_path / out,
            "--probabilities", "--descriptors", timeout=120)
    pcd = primlabel.pcd.read(tmp_path / "labeled.pcd")
    ply = primlabel.read(tmp_path / "labeled.ply")
    assert ply.fields.keys() == pcd.fields.keys()
    # The descriptor columns (named by the model's descriptor: fpfh, fpfh_paper or pfh,
    # written as <name>_0 .. <name>_32) are one (N, 33) field again, as in the PCD.
    (descriptor,) = [name for name, values in ply.fields.items() if np.ndim(values) == 2]
    assert descriptor.startswith("fpfh") and ply.fields[descriptor].shape == (len(pcd), 33)
    assert any(name.startswith("prob_") for name in ply.fields)
    np.testing.assert_array_equal(ply.xyz, pcd.xyz)
    np.testing.assert_array_equal(ply.label, pcd.label)
    if pcd.rgb is not None:  # the synthetic scan's colours: PCD rgba, PLY red green blue alpha
        np.testing.assert_array_equal(ply.rgb, pcd.rgb)
    for name, values in pcd.fields.items():
        np.testing.assert_array_equal(ply.fields[name], values, err_msg=name)
    raw = (tmp_path / "labeled.ply").read_bytes()
    assert b"format binary_little_endian" in raw.split(b"end_header", 1)[0]
    for encoding in ("ascii", "binary_big_endian"):
        other = tmp_path / f"labeled-{encoding}.ply"
        other.write_bytes(reencoded(raw, encoding, len(pcd)))
        again = primlabel.ply.read(other)
        np.testing.assert_array_equal(again.xyz, pcd.xyz)
        np.testing.assert_array_equal(again.label, pcd.label)
        for name, values in pcd.fields.items():
            np.testing.assert_array_equal(again.fields[name], values, err_msg=name)
