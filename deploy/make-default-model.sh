#!/usr/bin/env bash
# Writes the default model repository (<OUT_DIR>/<model>/<version>/model.plm) that the container
# image ships at /models. A thin wrapper: the training recipe lives in deploy/setup.sh, so the
# image and a developer's machine make the same model.
#
#   deploy/make-default-model.sh OUT_DIR
set -euo pipefail

if [[ $# -ne 1 ]]; then
  echo "usage: $0 OUT_DIR" >&2
  exit 2
fi
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT_DIR=$1
mkdir -p "$OUT_DIR"
"$ROOT/deploy/setup.sh" default-model "$OUT_DIR"

# The server loads <dir>/<model>/<version>/model.plm: refuse to bake an image without one.
if ! compgen -G "$OUT_DIR/*/*/model.plm" >/dev/null; then
  echo "$0: no <model>/<version>/model.plm under $OUT_DIR" >&2
  exit 1
fi
