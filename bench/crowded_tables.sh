#!/usr/bin/env bash
# The table-top stage on crowded tables with their hard cases (issue 45): objects in contact,
# stacks of nearly one footprint, boxes and books leaning on boxes, cans beside boxes of their
# height and colour. Writes FRAMES simulated Kinect frames c01.pcd.. (`primlabel-synth --scene
# crowded --sensor kinect --seed N --segment-labels`, N = 1..FRAMES) into OUT_DIR and prints
# `primlabel-bench tabletop --compare-pcl --repeat 1` on them: a line per frame, totals for odd,
# even and all frames, then the JSON line. A build without PCL refuses --compare-pcl; the
# script then says so and prints our figures alone. Opt-in (about 1 min on 2 cores).
#
#   bench/crowded_tables.sh [BUILD_DIR] [OUT_DIR] [FRAMES]
#
# Defaults: build, a temporary directory removed at exit, 20 frames (the set docs/results.md
# measures under "Crowded tables").
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${1:-$ROOT/build}
OUT=${2:-}
FRAMES=${3:-20}
BIN=$BUILD_DIR/bin
for tool in primlabel-synth primlabel-bench; do
  [[ -x "$BIN/$tool" ]] || { echo "crowded_tables.sh: $BIN/$tool missing (build first)" >&2; exit 2; }
done
[[ "$FRAMES" =~ ^[1-9][0-9]*$ ]] || { echo "crowded_tables.sh: FRAMES must be a positive number" >&2; exit 2; }
errors=$(mktemp)
made_out=""
trap 'rm -f "$errors"; if [[ -n "$made_out" ]]; then rm -rf "$made_out"; fi' EXIT
if [[ -z "$OUT" ]]; then
  OUT=$(mktemp -d)
  made_out=$OUT
else
  mkdir -p "$OUT"
fi

frames=()
for seed in $(seq 1 "$FRAMES"); do
  frame=$(printf '%s/c%02d.pcd' "$OUT" "$seed")
  timeout 120 "$BIN/primlabel-synth" --scene crowded --sensor kinect --seed "$seed" \
    --segment-labels -q -o "$frame"
  frames+=("$frame")
done
echo "crowded_tables.sh: $FRAMES frames in $OUT (seeds 1-$FRAMES)" >&2

# The bench checks for PCL before reading any frame, so a refusal costs nothing.
if timeout 1800 "$BIN/primlabel-bench" tabletop --compare-pcl --repeat 1 "${frames[@]}" 2>"$errors"; then
  cat "$errors" >&2
  exit 0
fi
if grep -q -- '--compare-pcl needs PCL' "$errors"; then
  cat "$errors" >&2
  echo "crowded_tables.sh: no PCL in this build: ours alone, the PCL columns stay empty" >&2
  timeout 1800 "$BIN/primlabel-bench" tabletop --repeat 1 "${frames[@]}"
else
  cat "$errors" >&2
  exit 1
fi
