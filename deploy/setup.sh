#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine: installs what is missing, builds, then runs.
#
#   deploy/setup.sh run     install + build + the main job (features of the bundled sample)
#   deploy/setup.sh test    install + build + the whole test suite (CTest)
#   deploy/setup.sh build   install + build only
#   deploy/setup.sh deps    install only
#   deploy/setup.sh default-model [DIR]
#                           install + build + the default model into DIR (a model repository,
#                           default build/models): DIR/tabletop-lms400/1/model.plm
#
# Environment: BUILD_DIR (default build), BUILD_TYPE (Release), JOBS (nproc),
#              PRIMLABEL_WITH_PCL=1 also installs libpcl-dev so benchmarks compare against PCL,
#              CMAKE_ARGS extra arguments for cmake (e.g. -DPRIMLABEL_NATIVE=ON).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
BUILD_TYPE=${BUILD_TYPE:-Release}
JOBS=${JOBS:-$(nproc)}

# Debian 12 packages the build and the tests need.
PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libnanoflann-dev liblzf-dev libcli11-dev libpng-dev zlib1g-dev
  libprotobuf-dev protobuf-compiler liblbfgspp-dev libsvm-dev
  libgrpc++-dev protobuf-compiler-grpc
  libgtest-dev
  python3-yaml nginx prometheus
)
[[ "${PRIMLABEL_WITH_PCL:-0}" == 1 ]] && PACKAGES+=(libpcl-dev)

log() { echo "[setup] $*" >&2; }

install_packages() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [[ ${#missing[@]} -eq 0 ]]; then
    log "all ${#PACKAGES[@]} packages present"
    return
  fi
  log "installing: ${missing[*]}"
  local sudo=()
  [[ $(id -u) -ne 0 ]] && sudo=(sudo)
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
}

build() {
  # shellcheck disable=SC2086
  cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" ${CMAKE_ARGS:-} >/dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

# The default model: CRF + FPFH from 8 synthetic LMS400 table scenes (fixed seeds), so the same
# commands make the same model. Kept when it exists.
default_model() {
  local repo=${1:-$BUILD_DIR/models}
  local model="$repo/tabletop-lms400/1/model.plm"
  if [[ -f "$model" ]]; then
    log "default model present: $model"
    return
  fi
  mkdir -p "$(dirname "$model")"
  "$BUILD_DIR/bin/primlabel-train" --sensor lms400 --kind crf --name tabletop-lms400 \
    --curve "$(dirname "$model")/training_curve.csv" -o "$model.tmp"
  mv "$model.tmp" "$model"
  log "wrote the default model $model"
}

run_main_job() {
  local out="$BUILD_DIR/out"
  mkdir -p "$out"
  "$BUILD_DIR/bin/primlabel-features" "$ROOT/tests/data/samples/bun0.pcd" \
    -o "$out/bun0_features.pcd" --normal-k 10 --feature-radius 0.02 --viewpoint 0,0,0
  log "wrote $out/bun0_features.pcd (x y z, normals, curvature, fpfh 33)"
}

run_tests() {
  ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" --timeout 600
}

case "${1:-}" in
  deps) install_packages ;;
  default-model) install_packages; build; default_model "${2:-}" ;;
  build) install_packages; build ;;
  run) install_packages; build; run_main_job ;;
  test) install_packages; build; run_tests ;;
  *) echo "usage: $0 run|test|build|deps" >&2; exit 2 ;;
esac
