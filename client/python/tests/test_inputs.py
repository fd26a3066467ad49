"""What label() and label_unary() take besides an (N, 3) array: a path to a PCD or PLY file (read
as the CLI reads it, sent from the PCD's VIEWPOINT) and Open3D clouds (their points), without the
client importing Open3D itself."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import primlabel


@pytest.fixture(scope="module")
def cloud(scan):
    return primlabel.pcd.read(scan)


@pytest.fixture(scope="module")
def from_its_viewpoint(server, cloud):
    """The labels of the scan's points sent as an array from the PCD's VIEWPOINT."""
    with primlabel.Client(server.address, deadline=30) as c:
        return c.label(cloud.xyz, viewpoint=cloud.viewpoint[:3]).labels


@pytest.fixture(scope="module")
def from_the_origin(server, cloud):
    """The labels of the scan's points sent as an array with no viewpoint (the origin)."""
    with primlabel.Client(server.address, deadline=30) as c:
        return c.label(cloud.xyz).labels


def write_ply(path: Path, xyz: np.ndarray) -> None:
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(xyz)}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n")
    path.write_bytes(header.encode() + np.ascontiguousarray(xyz, "<f4").tobytes())


@pytest.mark.parametrize("call", ["label", "label_unary"])
def test_a_pcd_path_is_read_and_sent_from_its_viewpoint(client, scan, call, from_its_viewpoint):
    # As the CLI does: `primlabel label scan.pcd` sends the scan from its VIEWPOINT.
    assert primlabel.pcd.read(scan).viewpoint[:3] != (0, 0, 0)
    for path in (str(scan), Path(scan)):
        result = getattr(client, call)(path)
        np.testing.assert_array_equal(result.labels, from_its_viewpoint)


def test_a_given_viewpoint_wins_over_the_file_s(client, scan, from_the_origin):
    result = client.label(scan, viewpoint=(0, 0, 0))
    np.testing.assert_array_equal(result.labels, from_the_origin)


def test_a_ply_path_is_read_and_sent(client, cloud, tmp_path, from_the_origin):
    path = tmp_path / "scan.ply"
    write_ply(path, cloud.xyz)  # a PLY has no viewpoint: the origin, as the CLI has it
    np.testing.assert_array_equal(client.label(path).labels, from_the_origin)
    np.testing.assert_array_equal(client.label_unary(str(path)).labels, from_the_origin)


def test_a_bad_path_is_refused_before_any_call(client, tmp_path):
    for path, message in ((tmp_path / "missing.pcd", "cannot open"),
                          (str(tmp_path / "scan.xyz"), "unknown point cloud format")):
        with pytest.raises(primlabel.InvalidInput, match=message):
            client.label(path)


@pytest.mark.parametrize("call", ["label", "label_unary"])
def test_open3d_clouds_send_their_points(client, cloud, call, from_the_origin,
                                         from_its_viewpoint):
    o3d = pytest.importorskip("open3d")
    legacy = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud.xyz.astype(np.float64)))
    tensor = o3d.t.geometry.PointCloud(o3d.core.Tensor(cloud.xyz))
    for o3d_cloud in (legacy, tensor):
        label = getattr(client, call)
        np.testing.assert_array_equal(label(o3d_cloud).labels, from_the_origin)
        np.testing.assert_array_equal(label(o3d_cloud, viewpoint=cloud.viewpoint[:3]).labels,
                                      from_its_viewpoint)
    # An empty tensor cloud has no positions at all: it is an empty (0, 3) array.
    assert primlabel.client._points_of(o3d.t.geometry.PointCloud()).shape == (0, 3)


def test_any_object_with_points_will_do(client, cloud, from_the_origin):
    class Cloud:  # Open3D's shape, without Open3D
        points = cloud.xyz.tolist()

    np.testing.assert_array_equal(client.label(Cloud()).labels, from_the_origin)


def test_the_client_does_not_import_open3d():
    env = dict(os.environ)
    code = "import sys, primlabel; print('open3d' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], env=env, timeout=60,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"
