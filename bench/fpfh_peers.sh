#!/usr/bin/env bash
# FPFH throughput of primlabel against PCL and Open3D in the same run, on the same points with the
# same (primlabel's) normals, the same radius and threads. Stage times exclude each library's
# k-d tree build. Prints each run's figures and one JSON line per input with both ratios.
#
#   bench/fpfh_peers.sh [BUILD_DIR] [INPUT...]
#
# Defaults: build, and ../shared/data/mosd/learn0.pcd whole and cropped to its 29,000 points
# nearest the centroid. Environment: THREADS (2), REPEAT (3), NORMAL_RADIUS (0.015),
# FEATURE_RADIUS (0.03). Needs a build with PCL (PRIMLABEL_WITH_PCL=1 deploy/setup.sh build) and
# Debian's python3-open3d; exit 77 when either is missing.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${1:-$ROOT/build}
shift || true
THREADS=${THREADS:-2} REPEAT=${REPEAT:-3}
NORMAL_RADIUS=${NORMAL_RADIUS:-0.015} FEATURE_RADIUS=${FEATURE_RADIUS:-0.03}
LEARN0=$ROOT/../shared/data/mosd/learn0.pcd
PY=/usr/bin/python3  # Debian's, where python3-open3d lives
"$PY" -c 'import open3d' 2>/dev/null || { echo "fpfh_peers.sh: python3-open3d missing" >&2; exit 77; }
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

run() {  # LABEL INPUT [features flags...]
  local label=$1 input=$2
  shift 2
  echo "== $label" >&2
  local ours
  ours=$(OMP_NUM_THREADS=$THREADS "$BUILD_DIR/bin/primlabel-bench" features "$input" \
    --normal-radius "$NORMAL_RADIUS" --feature-radius "$FEATURE_RADIUS" --threads "$THREADS" \
    --repeat "$REPEAT" --descriptor fpfh --compare-pcl --write-cloud "$WORK/cloud.ply" "$@") ||
    { local rc=$?; [[ $rc == 2 ]] && exit 77; exit "$rc"; }
  local theirs
  theirs=$(OMP_NUM_THREADS=$THREADS "$PY" "$ROOT/bench/open3d_fpfh.py" "$WORK/cloud.ply" \
    "$FEATURE_RADIUS" --repeat "$REPEAT")
  "$PY" - "$label" "$ours" "$theirs" <<'PYEOF'
import json, sys
label, ours, theirs = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3])
out = {"input": label, "points": ours["points"], "threads": ours["threads"],
       "fpfh_pts_s": ours["fpfh_pts_s"], "pcl_fpfh_pts_s": ours.get("pcl_fpfh_pts_s"),
       "o3d_fpfh_pts_s": theirs["o3d_fpfh_pts_s"],
       "vs_pcl": ours["fpfh_pts_s"] / ours["pcl_fpfh_pts_s"],
       "vs_open3d": ours["fpfh_pts_s"] / theirs["o3d_fpfh_pts_s"]}
print(f"{label}: {out['points']} points, primlabel {out['fpfh_pts_s']:.0f} pts/s, "
      f"{out['vs_pcl']:.1f}x PCL, {out['vs_open3d']:.1f}x Open3D", file=sys.stderr)
print(json.dumps(out))
PYEOF
}

if [[ $# -eq 0 ]]; then
  [[ -f "$LEARN0" ]] || { echo "fpfh_peers.sh: $LEARN0 missing" >&2; exit 77; }
  run learn0 "$LEARN0"
  run learn0-crop29k "$LEARN0" --crop 29000
else
  for input in "$@"; do run "$(basename "$input")" "$input"; done
fi
