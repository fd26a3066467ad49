"""What the Open3D interop checks share: Open3D (or exit 77, skipped) and a synthetic scene."""
import subprocess
import sys
from pathlib import Path


def import_open3d():
    """numpy and open3d, or exit 77 (skipped) where python3-open3d is not installed."""
    try:
        import numpy as np
        import open3d as o3d
    except ImportError:
        print("python3-open3d not installed: skipped")
        sys.exit(77)
    return np, o3d


def synth_scene(build, path):
    """Writes the LMS400 scene of seed 5 to `path` (.pcd or .ply) with the build's primlabel-synth."""
    subprocess.run([Path(build) / "bin/primlabel-synth", "--sensor", "lms400", "--seed", "5",
                    "-o", path, "-q"], check=True)
