"""primlabel.pcd against known files and the C++ reader and writer: PCL's bun0 (ascii), the mOSD
frames (binary_compressed, organised), round trips, the C++ CLI reading what Python wrote and
Python reading what the CLI wrote (binary_compressed through liblzf), malformed files."""

from __future__ import annotations

import numpy as np
import pytest

import primlabel
from conftest import SHARED_DATA, TEST_DATA, binary, run
from primlabel import pcd


def full_cloud() -> pcd.PointCloud:
    """An organised 3 x 4 cloud with every kind of field, NaN pixels and a viewpoint."""
    rng = np.random.default_rng(5)
    xyz = rng.normal(size=(12, 3)).astype(np.float32)
    xyz[[2, 7]] = np.nan
    return pcd.PointCloud(
        xyz=xyz,
        normals=rng.normal(size=(12, 3)).astype(np.float32),
        curvature=rng.uniform(size=12).astype(np.float32),
        label=np.arange(12, dtype=np.uint32) * 357913941,  # up to 2^32 - 1
        rgb=np.array([0xFF102030 + i for i in range(12)], dtype=np.uint32),
        fields={
            "fpfh": rng.uniform(0, 100, size=(12, 33)).astype(np.float32),
            "intensity": rng.uniform(size=12).astype(np.float32),
            "ring": np.arange(12, dtype=np.float32),
        },
        width=4,
        height=3,
        viewpoint=(0.5, -1.25, 2.0, 0.0, 1.0, 0.0, 0.0),
    )


def assert_same(a: pcd.PointCloud, b: pcd.PointCloud) -> None:
    for name in ("xyz", "normals", "curvature", "label", "rgb"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype, name
        np.testing.assert_array_equal(x, y, err_msg=name)
    assert a.fields.keys() == b.fields.keys()
    for name in a.fields:
        assert a.fields[name].dtype == b.fields[name].dtype, name
        np.testing.assert_array_equal(a.fields[name], b.fields[name], err_msg=name)
    assert (a.width, a.height, tuple(a.viewpoint)) == (b.width, b.height, tuple(b.viewpoint))


@pytest.mark.parametrize("encoding", ["ascii", "binary", "binary_compressed"])
def test_round_trip_keeps_every_field_exactly(tmp_path, encoding):
    cloud = full_cloud()
    path = tmp_path / f"cloud_{encoding}.pcd"
    pcd.write(path, cloud, encoding=encoding)
    back = pcd.read(path)
    assert_same(cloud, back)
    assert back.organized and back.grid(back.xyz).shape == (3, 4, 3)
    assert f"DATA {encoding}\n" in path.read_bytes().decode("latin-1")


def test_other_types_are_written_as_the_service_s_float32(tmp_path):
    # The C++ writer's PointCloud holds float32 coordinates and fields: float64 and integer
    # arrays are converted, labels and colours stay uint32.
    cloud = pcd.PointCloud(xyz=np.arange(6, dtype=np.float64).reshape(2, 3) / 4,
                           label=np.array([7, 4294967295], np.int64),
                           fields={"ring": np.array([1, 2], np.uint16), "t": np.array([0.5, 2])})
    path = tmp_path / "types.pcd"
    pcd.write(path, cloud)
    back = pcd.read(path)
    assert back.xyz.dtype == np.float32 and back.label.dtype == np.uint32
    np.testing.assert_array_equal(back.xyz, cloud.xyz)
    np.testing.assert_array_equal(back.label, cloud.label)
    for name, values in cloud.fields.items():
        assert back.fields[name].dtype == np.float32
        np.testing.assert_array_equal(back.fields[name], values)


def test_multi_value_fields_are_also_written_as_columns_and_folded_back(tmp_path):
    cloud = pcd.PointCloud(xyz=np.zeros((2, 3), np.float32))
    cloud.fields["fpfh"] = np.arange(6, dtype=np.float32).reshape(2, 3)
    path = tmp_path / "columns.pcd"
    pcd.write(path, cloud, encoding="ascii")
    text = path.read_text()
    assert "FIELDS x y z fpfh fpfh_0 fpfh_1 fpfh_2\n" in text
    assert "\n0 0 0 0 1 2 0 1 2\n0 0 0 3 4 5 3 4 5\n" in text
    back = pcd.read(path)
    assert list(back.fields) == ["fpfh"]
    np.testing.assert_array_equal(back.fields["fpfh"], cloud.fields["fpfh"])
    # A column beyond the field's COUNT is a field of its own.
    path.write_text("VERSION 0.7\nFIELDS x y z h h_1 h_2\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\n"
                    "COUNT 1 1 1 2 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0 1 2 2 9\n")
    assert list(pcd.read(path).fields) == ["h", "h_2"]


def test_bun0_ascii_as_the_file_says():
    cloud = pcd.read(TEST_DATA / "samples" / "bun0.pcd")
    assert len(cloud) == 397 and not cloud.organized and cloud.width == 397
    np.testing.assert_array_equal(cloud.xyz[0], np.float32([0.0054215998, 0.11349, 0.040748999]))
    np.testing.assert_array_equal(cloud.normals[0],
                                  np.float32([-0.16884723, -0.45159745, -0.87609947]))
    assert cloud.curvature[0] == np.float32(0.0030943851)
    assert cloud.label is None and cloud.rgb is None and cloud.fields == {}


def test_mosd_binary_compressed_frame():
    path = SHARED_DATA / "mosd" / "learn0.pcd"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    cloud = pcd.read(path)
    assert (cloud.width, cloud.height, len(cloud)) == (640, 480, 307200)
    assert cloud.rgb.dtype == np.uint32 and cloud.label.dtype == np.uint32
    # The dataset's rule (shared/data/README.md): label 0 exactly where the depth is missing.
    missing = np.isnan(cloud.xyz).any(axis=1)
    assert 0 < missing.sum() < len(cloud)
    np.testing.assert_array_equal(cloud.label == 0, missing)
    # Kinect depths in metres, in front of the camera.
    depth = cloud.grid(cloud.xyz)[..., 2]
    assert 0.3 < np.nanmin(depth) < np.nanmax(depth) < 10


def test_the_cli_reads_what_python_writes_and_python_reads_what_it_writes(server, scan, tmp_path):
    """Python-written ascii and binary files labeled by the C++ CLI, whose output is
    binary_compressed (liblzf): the same points and the same labels as Python's own call."""
    cloud = pcd.read(scan)
    subset = pcd.PointCloud(xyz=cloud.xyz[:20000], viewpoint=cloud.viewpoint)
    with primlabel.Client(server.address) as client:
        expected = client.label(subset).labels
    for encoding in ("ascii", "binary", "binary_compressed"):
        written = tmp_path / f"subset_{encoding}.pcd"
        pcd.write(written, subset, encoding=encoding)
        out = tmp_path / f"subset_{encoding}_labeled.pcd"
        run(binary("primlabel"), "--server", server.address, "label", written, "-o", out)
        assert b"DATA binary_compressed" in out.read_bytes()[:1000]
        labeled = pcd.read(out)
        np.testing.assert_array_equal(labeled.xyz, subset.xyz)
        np.testing.assert_array_equal(labeled.label, expected)


def test_binary_compressed_mosd_frame_rewritten_is_smaller_and_equal(tmp_path):
    path = SHARED_DATA / "mosd" / "learn0.pcd"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    cloud = pcd.read(path)
    out = tmp_path / "learn0_again.pcd"
    pcd.write(out, cloud, encoding="binary_compressed")
    assert out.stat().st_size < 0.8 * len(cloud) * 20  # x y z rgba label: 20 bytes a point
    back = pcd.read(out)
    np.testing.assert_array_equal(back.xyz, cloud.xyz)  # NaN pixels in the same places
    np.testing.assert_array_equal(back.label, cloud.label)
    np.testing.assert_array_equal(back.rgb, cloud.rgb)
    assert (back.width, back.height) == (640, 480)


def test_empty_cloud_binary_compressed(tmp_path):
    out = tmp_path / "empty.pcd"
    pcd.write(out, pcd.PointCloud(xyz=np.zeros((0, 3), np.float32)), encoding="binary_compressed")
    assert len(pcd.read(out)) == 0


HEADER = ("VERSION 0.7\nFIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F {label_type}\nCOUNT 1 1 1 1\n"
          "WIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA {data}\n")


@pytest.mark.parametrize("text,message", [
    (HEADER.format(label_type="I", n=1, data="ascii") + "1 2 3 -4\n", "is not a label"),
    (HEADER.format(label_type="U", n=2, data="ascii") + "1 2 3 4\n",
     "ascii data ends after 1 points, POINTS declares 2"),
    (HEADER.format(label_type="U", n=1, data="ascii") + "1 2 3\n", "expected 4 values"),
    (HEADER.format(label_type="U", n=1, data="ascii") + "1 2 x 4\n", "field 'z'"),
    (HEADER.format(label_type="U", n=1000000, data="binary") + "abcd", "truncated binary"),
    (HEADER.format(label_type="U", n=10, data="binary_compressed") + "\x10\0\0\0\xa0\0\0\0",
     "larger than the"),
    (HEADER.format(label_type="U", n=9, data="binary_compressed") + "\x10\0\0\0\xa0\0\0\0",
     "uncompressed"),
    (HEADER.format(label_type="U", n=1, data="ascii").replace("DATA ascii\n", ""), "missing DATA"),
    ("VERSION 0.7\nFIELDS x y\nDATA ascii\n", "missing field 'z'"),
    ("VERSION 0.7\nFIELDS x y z rgb rgba\nPOINTS 0\nDATA ascii\n", "both 'rgb' and 'rgba'"),
    ("", "empty file"),
])
def test_malformed_files_say_what_is_wrong(tmp_path, text, message):
    path = tmp_path / "bad.pcd"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(pcd.PcdError) as error:
        pcd.read(path)
    assert str(error.value).startswith(str(path)) and message in str(error.value)


def test_unwritable_clouds_are_refused(tmp_path):
    with pytest.raises(pcd.PcdError):
        pcd.write(tmp_path / "a.pcd", pcd.PointCloud(xyz=np.zeros((4, 3)), width=3))
    with pytest.raises(pcd.PcdError):
        pcd.write(tmp_path / "a.pcd", pcd.PointCloud(xyz=np.zeros((4, 3)), label=np.zeros(3)))
    with pytest.raises(pcd.PcdError):
        pcd.write(tmp_path / "a.pcd", pcd.PointCloud(xyz=np.zeros((4, 3)),
                                                     fields={"bad name": np.zeros(4)}))
    assert not list(tmp_path.iterdir())
