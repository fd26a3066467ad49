#!/usr/bin/python3
"""Open3D reads every value of the descriptors primlabel writes into PCD files.

Usage: open3d_reads_descriptors.py BUILD_DIR. PCL's form of FPFH is one field of COUNT 33, of
which Open3D's tensor reader keeps only the first value; primlabel also writes the columns
fpfh_0 .. fpfh_32. Checks that Open3D finds all 33, that column 0 is the value it read for
`fpfh`, and that each point's histogram sums to 300 (three sub-histograms of 100) or is empty.
Exits 77 (skipped) without open3d.
"""
import subprocess
import sys
import tempfile
from pathlib import Path

from open3d_support import import_open3d, synth_scene

np, o3d = import_open3d()

build = Path(sys.argv[1])
with tempfile.TemporaryDirectory() as tmp:
    scene = Path(tmp) / "scene.pcd"
    features = Path(tmp) / "features.pcd"
    synth_scene(build, scene)
    subprocess.run([build / "bin/primlabel-features", scene, "-o", features], check=True,
                   stdout=subprocess.DEVNULL)
    cloud = o3d.t.io.read_point_cloud(str(features))
    names = [f"fpfh_{e}" for e in range(33)]
    missing = [n for n in names if n not in cloud.point]
    assert not missing, f"Open3D found no {missing[:3]}...: {cloud.point}"
    histograms = np.hstack([cloud.point[n].numpy() for n in names])
    assert len(histograms) > 1000, histograms.shape
    assert np.array_equal(histograms[:, 0], cloud.point["fpfh"].numpy().ravel())
    sums = histograms.sum(axis=1)
    described = sums > 0
    assert described.mean() > 0.9, f"only {described.mean():.1%} of the points have a histogram"
    assert np.allclose(sums[described], 300, rtol=1e-3), sums[described][:5]
    print(f"Open3D read all 33 FPFH values of {len(histograms)} points from a primlabel PCD")
