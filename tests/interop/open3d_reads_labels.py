#!/usr/bin/python3
"""Open3D reads the labels primlabel writes into PLY files (issue 17: it skipped "uint" ones).

Usage: open3d_reads_labels.py BUILD_DIR. Writes a synthetic labeled scene as PLY, reads it with
Open3D's tensor reader and checks every point's label against the file's body read with numpy
from the header's layout. Exits 77 (skipped) without open3d.
"""
import sys
import tempfile
from pathlib import Path

from open3d_support import import_open3d, synth_scene

np, o3d = import_open3d()

build = Path(sys.argv[1])
with tempfile.TemporaryDirectory() as tmp:
    ply = Path(tmp) / "scene.ply"
    synth_scene(build, ply)
    cloud = o3d.t.io.read_point_cloud(str(ply))
    assert "label" in cloud.point, f"Open3D found no label attribute: {cloud.point}"
    labels = cloud.point["label"].numpy().ravel()
    positions = cloud.point["positions"].numpy()
    assert len(labels) == len(positions) > 1000, (len(labels), len(positions))
    # The same labels read straight from the binary body with the header's own layout.
    data = ply.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    types = {"float": "<f4", "uint": "<u4", "int": "<i4", "uchar": "u1", "double": "<f8"}
    fields = [line.split()[1:] for line in data[:end].decode().splitlines()
              if line.startswith("property ")]
    body = np.frombuffer(data[end:], dtype=np.dtype([(n, types[t]) for t, n in fields]))
    assert body["label"].dtype == np.int32, "labels that fit an int are written as int"
    assert np.array_equal(labels, body["label"]), "Open3D's labels differ from the file's"
    assert np.allclose(positions[:, 0], body["x"])
    theirs = np.unique(labels)
    print(f"Open3D read {len(labels)} labels, {len(theirs)} classes, as primlabel does")
