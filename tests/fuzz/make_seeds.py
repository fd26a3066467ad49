#!/usr/bin/env python3
"""Writes the seed corpora in tests/fuzz/corpus/: a few tiny PCD and PLY files in every encoding
the readers take, and serialized Label / LabelCloud requests (encoded by protoc from text).
Run from anywhere: python3 tests/fuzz/make_seeds.py (needs protoc)."""
import os
import struct
import subprocess

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
POINTS = [(0.0, 0.0, 1.0, 1), (0.5, -0.25, 1.5, 2), (float("nan"), 0.0, 0.0, 0)]


def write(target, name, data):
    os.makedirs(os.path.join(HERE, "corpus", target), exist_ok=True)
    with open(os.path.join(HERE, "corpus", target, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def pcd_header(fields, sizes, types, counts, width, height, data):
    return ("# .PCD v0.7\nVERSION 0.7\nFIELDS %s\nSIZE %s\nTYPE %s\nCOUNT %s\nWIDTH %d\n"
            "HEIGHT %d\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %d\nDATA %s\n" %
            (fields, sizes, types, counts, width, height, width * height, data))


def lzf_literal(raw):
    """An LZF stream of literal runs only (at most 32 bytes each): valid, just not compressed."""
    out = b""
    for i in range(0, len(raw), 32):
        run = raw[i:i + 32]
        out += bytes([len(run) - 1]) + run
    return out


def pcd_seeds():
    fields = ("x y z label", "4 4 4 4", "F F F U", "1 1 1 1")
    ascii_rows = "".join("%s %s %s %d\n" % (x, y, z, l) for x, y, z, l in POINTS)
    write("pcd_reader", "ascii.pcd", pcd_header(*fields, 3, 1, "ascii") + ascii_rows)
    records = b"".join(struct.pack("<fffI", *p) for p in POINTS)
    write("pcd_reader", "binary.pcd", pcd_header(*fields, 3, 1, "binary").encode() + records)
    planes = b"".join(
        b"".join(struct.pack("<" + t, p[i]) for p in POINTS) for i, t in enumerate("fffI"))
    compressed = lzf_literal(planes)
    write("pcd_reader", "binary_compressed.pcd",
          pcd_header(*fields, 3, 1, "binary_compressed").encode() +
          struct.pack("<II", len(compressed), len(planes)) + compressed)
    # Organised 2x2, with an rgb colour, a padding field and a field of count 2.
    organised = pcd_header("x y z rgb _ extra", "4 4 4 4 1 2", "F F F U U I", "1 1 1 1 1 2", 2, 2,
                           "ascii")
    organised += "".join("%d %d 1 %d 0 -3 7\n" % (i % 2, i // 2, 0xff0000 + i) for i in range(4))
    write("pcd_reader", "organised_ascii.pcd", organised)
    # A zero-area shape with no POINTS line (a past finding: the cloud came back 3 wide, 0 long).
    write("pcd_reader", "zero_area_binary.pcd",
          "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 0\nDATA binary\n")


def ply_seeds():
    head = ("ply\nformat %s 1.0\ncomment seed\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
            "property uchar blue\nproperty float nx\nproperty float ny\nproperty float nz\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n")
    rows = [(x, y, z, 10 * i, 20, 30, 0.0, 0.0, 1.0) for i, (x, y, z, _) in enumerate(POINTS)]
    write("ply_reader", "ascii.ply", head % "ascii" + "".join(
        "%s %s %s %d %d %d %s %s %s\n" % r for r in rows) + "3 0 1 2\n")
    for name, order in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        body = b"".join(struct.pack(order + "fffBBBfff", *r) for r in rows)
        body += struct.pack(order + "Biii", 3, 0, 1, 2)
        write("ply_reader", name + ".ply", (head % name).encode() + body)
    write("ply_reader", "labels_double.ply",
          "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
          "property double z\nproperty uint label\nproperty float fpfh_0\nproperty float fpfh_1\n"
          "end_header\n1 2 3 4 0.5 0.25\n-1 -2 -3 0 1 0\n")


def encode(message, text):
    return subprocess.run(
        ["protoc", "-I", os.path.join(ROOT, "proto"), "--encode=primlabel.v1." + message,
         os.path.join(ROOT, "proto", "primlabel", "v1", "labeling.proto")],
        input=text.encode(), stdout=subprocess.PIPE, check=True).stdout


def request_seeds():
    xyz = b"".join(struct.pack("<fff", *p[:3]) for p in POINTS)
    octal = "".join("\\%03o" % b for b in xyz)
    header = ('model: "tabletop" scan_id: "seed" viewpoint { z: 1 } '
              'options { voxel_size: 0.005 non_finite: NON_FINITE_DROP } expected_points: 3')
    unary = encode("LabelCloudRequest", 'header { %s } points { xyz: "%s" }' % (header, octal))
    write("request_decoding", "unary", b"\x00" + unary)
    normals = encode("LabelCloudRequest", 'header { layout { normals: true intensity: true } } '
                     'points { xyz: "%s" normals: "%s" intensity: "%s" }' %
                     (octal, octal, "\\000" * 12))
    write("request_decoding", "unary_normals", b"\x02" + normals)

    def framed(*messages):
        return b"\x01" + b"".join(struct.pack("<H", len(m)) + m for m in messages)

    first = encode("LabelRequest", "header { %s }" % header)
    chunk1 = encode("LabelRequest", 'chunk { xyz: "%s" }' % octal[:4 * 12 * 2])  # two points
    chunk2 = encode("LabelRequest", 'chunk { xyz: "%s" }' % octal[4 * 12 * 2:])
    end = encode("LabelRequest", "end { }")
    write("request_decoding", "stream", framed(first, chunk1, chunk2, end))
    reject = encode("LabelRequest",
                    "header { options { non_finite: NON_FINITE_REJECT } expected_points: 0 }")
    write("request_decoding", "stream_reject_nan",
          framed(reject, encode("LabelRequest", 'chunk { xyz: "%s" }' % octal)))


if __name__ == "__main__":
    pcd_seeds()
    ply_seeds()
    request_seeds()
