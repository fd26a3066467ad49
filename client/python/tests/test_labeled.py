"""primlabel.read gives a labeled file's class names (PointCloud.classes): from the header tag
the primlabel tools write (PCD and PLY), else from the .classes.json the CLI writes beside it;
None for a file that does not say."""

from __future__ import annotations

import json

import numpy as np

import primlabel
from primlabel import pcd

TAG = "0:unknown 1:plane 2:cylinder-convex"
EXPECTED = {0: "unknown", 1: "plane", 2: "cylinder-convex"}


def labeled_pcd_bytes(tag: str | None) -> bytes:
    header = "# .PCD v0.7 - Point Cloud Data file format\n"
    if tag is not None:
        header += "# primlabel model fake\n" f"# primlabel classes {tag}\n"
    header += ("VERSION 0.7\nFIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
               "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
               "0 0 1 1\n1 0 1 2\n")
    return header.encode()


def test_the_classes_tag_of_a_pcd_header(tmp_path):
    path = tmp_path / "scan_labeled.pcd"
    path.write_bytes(labeled_pcd_bytes(TAG))
    cloud = primlabel.read(path)
    assert cloud.classes == EXPECTED
    assert [cloud.classes[int(label)] for label in cloud.label] == ["plane", "cylinder-convex"]


def test_the_classes_tag_of_a_ply_header(tmp_path):
    path = tmp_path / "scan_labeled.ply"
    path.write_bytes(("ply\nformat ascii 1.0\ncomment primlabel model fake\n"
                      f"comment primlabel classes {TAG}\nelement vertex 1\nproperty float x\n"
                      "property float y\nproperty float z\nproperty uint label\nend_header\n"
                      "0 0 1 2\n").encode())
    assert primlabel.read(path).classes == EXPECTED


def test_the_json_beside_a_file_whose_header_lost_the_tag(tmp_path):
    path = tmp_path / "scan_labeled.pcd"
    path.write_bytes(labeled_pcd_bytes(None))  # as PCL resaves it: comments dropped
    (tmp_path / "scan_labeled.classes.json").write_text(json.dumps(
        {"model": "fake", "label_field": "label",
         "classes": [{"id": 0, "name": "unknown"}, {"id": 1, "name": "plane"},
                     {"id": 2, "name": "cylinder-convex"}]}))
    assert primlabel.read(path).classes == EXPECTED
    assert pcd.read(path).classes == EXPECTED


def test_a_file_that_does_not_say_has_no_classes(tmp_path):
    path = tmp_path / "plain.pcd"
    path.write_bytes(labeled_pcd_bytes(None))
    assert primlabel.read(path).classes is None
    (tmp_path / "plain.classes.json").write_text("{ not json")
    assert primlabel.read(path).classes is None
    # Nor is a cloud built in Python given any.
    assert pcd.PointCloud(xyz=np.zeros((1, 3), np.float32)).classes is None
