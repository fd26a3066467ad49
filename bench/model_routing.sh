#!/usr/bin/env bash
# Which model a bare server (`primlabel-server --models DIR`, no other flag) picks for requests
# that name none, and how long each takes through the service: held-out synthetic LMS400 scans
# and Kinect frames, the frames again sent unorganised (finite points only, VIEWPOINT kept, as a
# filtered ROS cloud arrives), and real mOSD frames organised and unorganised. One line per cloud:
# file, shape, the model, how it was chosen, seconds (CLI wall time). Opt-in (about 1 min).
#
#   bench/model_routing.sh [MODELS_DIR] [BUILD_DIR]
#
# Defaults: build/models (deploy/setup.sh default-model makes it) and build. Needs Debian's
# python3-numpy for the unorganised copies; ../shared/data/mosd for the real frames (else skipped).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
MODELS=${1:-$ROOT/build/models}
BUILD_DIR=${2:-$ROOT/build}
BIN=$BUILD_DIR/bin
MOSD=$ROOT/../shared/data/mosd
PY=/usr/bin/python3
[[ -d "$MODELS" ]] || { echo "model_routing.sh: no model repository $MODELS" >&2; exit 2; }
"$PY" -c 'import numpy' 2>/dev/null || { echo "model_routing.sh: python3-numpy missing" >&2; exit 77; }
WORK=$(mktemp -d)
server=""
trap '[[ -n "$server" ]] && kill "$server" 2>/dev/null; rm -rf "$WORK"' EXIT

inputs=()
for seed in 3000 3001 3002 3003; do
  "$BIN/primlabel-synth" --scene table --sensor lms400 --seed "$seed" -o "$WORK/lms400_$seed.pcd" >/dev/null 2>&1
  "$BIN/primlabel-synth" --scene table --sensor kinect --seed "$seed" -o "$WORK/kinect_$seed.pcd" >/dev/null 2>&1
  inputs+=("$WORK/lms400_$seed.pcd" "$WORK/kinect_$seed.pcd")
done
frames=("$WORK"/kinect_*.pcd)
for n in 0 5 11 23 30 41; do
  [[ -f "$MOSD/learn$n.pcd" ]] && frames+=("$MOSD/learn$n.pcd") && inputs+=("$MOSD/learn$n.pcd")
done
# The frames unorganised: their finite points as one row, the sensor's VIEWPOINT kept.
PYTHONPATH=$BUILD_DIR/python "$PY" - "$WORK" "${frames[@]}" <<'PYEOF'
import os, sys
import numpy as np
import primlabel
work = sys.argv[1]
for path in sys.argv[2:]:
    cloud = primlabel.pcd.read(path)
    keep = np.isfinite(cloud.xyz).all(axis=1)
    name = os.path.basename(path).replace(".pcd", "_unorganised.pcd")
    primlabel.pcd.write(os.path.join(work, name),
                        primlabel.pcd.PointCloud(xyz=cloud.xyz[keep], viewpoint=cloud.viewpoint))
PYEOF
inputs+=("$WORK"/*_unorganised.pcd)

"$BIN/primlabel-server" --models "$MODELS" --listen 127.0.0.1:0 --metrics-listen "" \
  --reload-seconds 0 >"$WORK/server.log" 2>&1 &
server=$!
port=""
for _ in $(seq 1 100); do
  port=$(sed -n 's/.*event=listening.* port=\([0-9]*\).*/\1/p' "$WORK/server.log" | head -n1)
  [[ -n "$port" ]] && break
  sleep 0.1
done
[[ -n "$port" ]] || { cat "$WORK/server.log" >&2; exit 1; }
grep -o 'event=default_model.*' "$WORK/server.log" >&2 || true
printf '%-32s %-9s %-16s %-8s %s\n' file shape model choice seconds
for input in "${inputs[@]}"; do
  line=$("$BIN/primlabel" --server "127.0.0.1:$port" label "$input" -o "$WORK/out.pcd" 2>&1 | tail -n1)
  shape=$(grep -a -m1 '^HEIGHT' "$input" | awk '{print ($2 > 1) ? "organised" : "unorg."}')
  model=$(sed -n 's/.* s, model \([^ ]*\) .*/\1/p' <<<"$line")
  choice=$(grep -o 'chosen by domain\|the default\|named by' <<<"$line" | head -n1 | awk '{print $NF}')
  seconds=$(sed -n 's/.* in \([0-9.]*\) s,.*/\1/p' <<<"$line")
  printf '%-32s %-9s %-16s %-8s %s\n' "$(basename "$input")" "$shape" "${model:-?}" "${choice:-?}" "${seconds:-?}"
done
