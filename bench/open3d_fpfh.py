#!/usr/bin/python3
"""Open3D's FPFH on a cloud with normals (a PLY from `primlabel-bench features --write-cloud`):
the peer of bench/fpfh_peers.sh. Prints one JSON line on stdout.

  open3d_fpfh.py CLOUD.ply RADIUS [--max-nn K] [--repeat N]

compute_fpfh_feature builds its own KDTreeFlann inside every call; that build is timed apart
(o3d_index_s) and subtracted for o3d_fpfh_pts_s, as primlabel's and PCL's stage times exclude
their index. Threads follow OMP_NUM_THREADS (Open3D uses OpenMP). Open3D's FPFH adds the
point's own SPFH, as primlabel's `paper` variant does.
"""
import argparse
import json
import sys
import time

try:
    import open3d as o3d
except ImportError:
    print("open3d_fpfh.py: python3-open3d is not installed", file=sys.stderr)
    sys.exit(77)


def best_seconds(repeat, fn):
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cloud")
    parser.add_argument("radius", type=float)
    parser.add_argument("--max-nn", type=int, default=0, help="0: every point in the radius")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    cloud = o3d.io.read_point_cloud(args.cloud)
    n = len(cloud.points)
    if n == 0 or not cloud.has_normals():
        print(f"open3d_fpfh.py: {args.cloud} has no points or no normals", file=sys.stderr)
        return 1
    search = (o3d.geometry.KDTreeSearchParamHybrid(args.radius, args.max_nn) if args.max_nn
              else o3d.geometry.KDTreeSearchParamRadius(args.radius))
    index_s = best_seconds(args.repeat, lambda: o3d.geometry.KDTreeFlann(cloud))
    total_s = best_seconds(
        args.repeat, lambda: o3d.pipelines.registration.compute_fpfh_feature(cloud, search))
    fpfh_s = max(total_s - index_s, 1e-9)
    print(f"Open3D {o3d.__version__}: FPFH on {n} points in {fpfh_s:.4f} s "
          f"({n / fpfh_s:.0f} pts/s; k-d tree {index_s:.4f} s, excluded)", file=sys.stderr)
    print(json.dumps({"o3d_version": o3d.__version__, "points": n, "o3d_index_s": index_s,
                      "o3d_fpfh_with_index_s": total_s, "o3d_fpfh_s": fpfh_s,
                      "o3d_fpfh_pts_s": n / fpfh_s}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
