#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine: installs what is missing, builds, then runs.
#
#   deploy/setup.sh run     install + build + the main job: the default models, then the labeling
#                           service on 127.0.0.1 labels a held-out LMS400 scan and a held-out
#                           Kinect frame sent by the primlabel CLI
#   deploy/setup.sh test    install + build + the whole test suite (CTest)
#   deploy/setup.sh build   install + build only
#   deploy/setup.sh deps    install only
#   deploy/setup.sh default-model [DIR]
#                           install + build + the default models into DIR (a model repository,
#                           default build/models): DIR/tabletop-lms400/1/model.plm,
#                           DIR/tabletop-kinect/1/model.plm and DIR/default_model (the model
#                           for requests naming none that no model's domain decides)
#   deploy/setup.sh kinect-model OUT [N...]
#                           (no install, no build) trains tabletop-kinect into OUT from the
#                           fitted truth of the mOSD learning scenes learnN (default 0-44) and
#                           the 8 synthetic scenes; to refresh deploy/models/tabletop-kinect.plm
#
# Environment: BUILD_DIR (default build), BUILD_TYPE (Release), JOBS (nproc),
#              PRIMLABEL_WITH_PCL=1 also installs libpcl-dev and libcgal-dev so benchmarks compare
#              against PCL and CGAL (`test` installs libcgal-dev too),
#              CMAKE_ARGS extra arguments for cmake (e.g. -DPRIMLABEL_NATIVE=ON),
#              BUILD_TARGETS builds only these targets (default: all; the image's build stage
#              names the three it needs), PRIMLABEL_IMAGE_PROOF=1 also installs podman, buildah
#              and debootstrap for deploy/image-proof.sh.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
BUILD_TYPE=${BUILD_TYPE:-Release}
JOBS=${JOBS:-$(nproc)}
# The default models' training augmentation (primlabel-train --augment).
DEFAULT_AUGMENT="noise=0.5:4,density=0.25:1,range=0.9:1.4,elevation=-10:10,copies=1"

# Debian 12 packages the build and the tests need.
PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libnanoflann-dev liblzf-dev libcli11-dev libpng-dev zlib1g-dev
  libprotobuf-dev protobuf-compiler liblbfgspp-dev libsvm-dev
  libgrpc++-dev protobuf-compiler-grpc
  prometheus-cpp-dev libcurl4-openssl-dev
  libssl-dev nlohmann-json3-dev
  libgtest-dev
)
# Only the tests need these: the deployment checks (YAML, nginx -t, promtool, the local
# three-replica proof), TLS certificates made on the fly, clang with libFuzzer for the fuzz
# targets (tests/fuzz), the Python client's runtime and pytest (client/python; its stubs come
# from protoc and protobuf-compiler-grpc's grpc_python_plugin, above, its PCD/PLY module from
# pybind11 and the Python headers) and what pip needs to
# install it offline into a venv (setuptools, wheel, pip, venv), Open3D for the
# interoperability check (tests/interop), CGAL for the Efficient RANSAC peer's test
# (tests/test_cgal_peer), ROS 1 (roscpp, sensor_msgs, std_msgs and rosmaster) for the ROS
# node client/ros and its test ros.LabelsPointCloud2, and Cyclone DDS (the C library and the
# idlc IDL compiler) for the ROS 2 node client/ros2 and its test ros2.LabelsPointCloud2.
TEST_PACKAGES=(python3 python3-yaml nginx prometheus openssl clang-14 libclang-rt-14-dev
  python3-grpcio python3-numpy python3-protobuf python3-pytest python3-open3d libcgal-dev
  pybind11-dev python3-dev
  python3-setuptools python3-wheel python3-pip python3-venv
  libroscpp-dev libsensor-msgs-dev libstd-msgs-dev python3-rosmaster
  cyclonedds-dev cyclonedds-tools)
# The benchmarks' peers: PCL (features, table-top) and CGAL's Efficient RANSAC (primitives).
[[ "${PRIMLABEL_WITH_PCL:-0}" == 1 ]] && PACKAGES+=(libpcl-dev libcgal-dev)
[[ "${1:-}" == test ]] && PACKAGES+=("${TEST_PACKAGES[@]}")
# Only deploy/image-proof.sh needs these (it builds the image from a debootstrapped base).
IMAGE_PROOF_PACKAGES=(podman buildah debootstrap fuse-overlayfs uidmap curl)
[[ "${PRIMLABEL_IMAGE_PROOF:-0}" == 1 ]] && PACKAGES+=("${IMAGE_PROOF_PACKAGES[@]}")

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
  local targets=()
  # shellcheck disable=SC2206
  [[ -n "${BUILD_TARGETS:-}" ]] && targets=(--target ${BUILD_TARGETS})
  cmake --build "$BUILD_DIR" -j "$JOBS" "${targets[@]}"
}

# The default model repository: one CRF + FPFH model per sensor, each from 8 synthetic table
# scenes (fixed seeds), so the same commands make the same models. Kept when they exist.
#
# tabletop-lms400: trained and served on 3 mm voxels (1.8x faster than full resolution: a scan's
#   ~500 points within 25 mm made every FPFH pass expensive), normals over 15 mm, FPFH over 30 mm
#   and class balance 0.25 (rare classes such as corners weigh more), each scene also scanned once
#   more with other noise, density, range and incidence (seeded by the scene), and shape evidence
#   (the table-top objects fitted with boxes and cylinders as model input). Held out
#   (tools/robustness_sweep.sh, 2026-12-06): 98.61% at 1x noise, 97.91% at 4x, 97.72% at 25%
#   density, corner recall 0.91 / 0.74 / 0.85 (without shape evidence 98.21%, 97.30%, 97.28%,
#   corners 0.55 / 0.67 / 0.51), for about 1.8x the time of a scan (307 -> 541 ms on 2 loaded
#   cores). About 2.5 min and 0.8 GB peak.
# tabletop-kinect: trained and served on 7 mm voxels (the model records the size and the server
#   applies it: a real 640x480 frame labels in 75-86 ms in process with the plane cascade, 157-185
#   at 5 mm, for 0.10 points of accuracy and 0.8 of object points in scene-level cross-validation,
#   2026-12-05, docs/results.md "Real-time path"), normals over 30 mm,
#   class balance 0.25, multi-scale input (FPFH also at 15 and 40 mm, surface variation at every
#   radius: +3 points of object accuracy in cross-validation, about 2.5x the CPU a frame),
#   no augmentation (it did not help on the real mOSD scenes), from the
#   fitted truth of the 45 real mOSD learning scenes (primlabel-research write-truth; its unknown
#   points are not trained on) beside the 8 synthetic Kinect scenes: it beat the synthetic-only
#   recipe in scene-level cross-validation (bench/real_crossval.sh). A fresh clone has no
#   ../shared/data/mosd, so every machine gets the committed deploy/models/tabletop-kinect.plm
#   (checked against its .sha256); `deploy/setup.sh kinect-model OUT` retrains it. docs/models.md "The default models" has its figures, time and memory.
LMS400_RECIPE=(--sensor lms400 --voxel-size 0.003 --normal-radius 0.015 --feature-radius 0.03
  --class-balance 0.25 --augment "$DEFAULT_AUGMENT" --shape-evidence)
KINECT_RECIPE=(--sensor kinect --voxel-size 0.007 --normal-radius 0.03 --class-balance 0.25
  --extra-radii 0.015,0.04 --surface-variation --synth-train 8)
MOSD_DIR=${MOSD_DIR:-$ROOT/../shared/data/mosd}
KINECT_MODEL=$ROOT/deploy/models/tabletop-kinect.plm
# Recorded in the model (TrainingSummary.data_attribution): ../shared/data/mosd/README.md.
MOSD_ATTRIBUTION="Real scans: the modified Object Segmentation Database (mOSD), learning scenes \
learn0-44, labels from primlabel's fitted ground truth. Original: Object Segmentation Database \
(OSD), A. Richtsfeld, Automation and Control Institute (ACIN), Vienna University of Technology; \
modified by S. Alexandrov, Bonn-Rhein-Sieg University of Applied Sciences; distributed with \
permission from A. Richtsfeld under the original dataset's licence (its repository: BSD-3-Clause, \
Copyright (c) 2013 Point Cloud Library)."

train_model() {  # REPO NAME RECIPE...: REPO/NAME/1/model.plm unless it exists
  local repo=$1 name=$2
  shift 2
  local model="$repo/$name/1/model.plm"
  if [[ -f "$model" ]]; then
    log "model present: $model"
    return
  fi
  mkdir -p "$(dirname "$model")"
  "$BUILD_DIR/bin/primlabel-train" --kind crf --name "$name" "$@" -o "$model.tmp"
  mv "$model.tmp" "$model"
  log "wrote $model"
}

# kinect_real_model OUT [N...]: tabletop-kinect from the fitted truth of the mOSD learning scenes
# learnN (default 0-44; the truth is written once into BUILD_DIR/mosd-truth) and the synthetic
# scenes. The model records the truth files as mosd-truth/learnN_truth.pcd.
kinect_real_model() {
  local out=$1
  shift
  local numbers=("$@") files=() scenes=() n
  ((${#numbers[@]})) || numbers=($(seq 0 44))
  local truth=$BUILD_DIR/mosd-truth
  for n in "${numbers[@]}"; do
    files+=("mosd-truth/learn${n}_truth.pcd")
    [[ -f "$truth/learn${n}_truth.pcd" ]] || scenes+=("$MOSD_DIR/learn$n.pcd")
  done
  if ((${#scenes[@]})); then
    log "writing the fitted truth of ${#scenes[@]} mOSD scenes into $truth"
    "$BUILD_DIR/bin/primlabel-research" write-truth "$truth" "${scenes[@]}" >/dev/null
  fi
  out=$(cd "$(dirname "$out")" && pwd)/$(basename "$out")
  (cd "$BUILD_DIR" && "$BUILD_DIR/bin/primlabel-train" --kind crf --name tabletop-kinect \
    "${KINECT_RECIPE[@]}" --train "${files[@]}" --attribution "$MOSD_ATTRIBUTION" -q -o "$out")
}

# tabletop-kinect into REPO: the committed file, checked against its checksum, on every machine
# alike (a fresh clone has no ../shared to retrain it from; `kinect-model` regenerates it and
# test_kinect_model retrains a subset where ../shared is).
kinect_model() {
  local model="$1/tabletop-kinect/1/model.plm"
  if [[ -f "$model" ]]; then
    log "model present: $model"
    return
  fi
  mkdir -p "$(dirname "$model")"
  (cd "$(dirname "$KINECT_MODEL")" && sha256sum --quiet -c "$(basename "$KINECT_MODEL").sha256") ||
    { log "$KINECT_MODEL does not match its checksum"; return 1; }
  cp "$KINECT_MODEL" "$model.tmp"
  mv "$model.tmp" "$model"
  log "wrote $model (the committed real-trained model)"
}

# What the default models are made from; a repository made by another recipe (or before the
# models recorded their domain, which routes requests that name no model) is retrained.
RECIPE_STAMP="domain-2 lms400: ${LMS400_RECIPE[*]} kinect: mosd learn0-44 ${KINECT_RECIPE[*]}"

default_models() {
  local repo=${1:-$BUILD_DIR/models}
  mkdir -p "$repo"
  if [[ "$(cat "$repo/.recipe" 2>/dev/null)" != "$RECIPE_STAMP" ]]; then
    [[ -d "$repo/tabletop-lms400/1" || -d "$repo/tabletop-kinect/1" ]] &&
      log "the default models in $repo come from another recipe: retraining them"
    rm -rf "$repo/tabletop-lms400/1" "$repo/tabletop-kinect/1"
  fi
  train_model "$repo" tabletop-lms400 "${LMS400_RECIPE[@]}"
  kinect_model "$repo"
  echo "$RECIPE_STAMP" >"$repo/.recipe"
  # The model for requests that name none and whose cloud no model's domain decides (an
  # unorganised cloud both models' spacing and noise fit): the server reads this file.
  [[ -f "$repo/default_model" ]] || echo tabletop-lms400 >"$repo/default_model"
}

# The main job: the default models served by primlabel-server on 127.0.0.1 with no other flag,
# and a held-out synthetic LMS400 scan and Kinect frame (test seeds, never trained on) labeled
# through it by the primlabel CLI, naming no model: the server sends each to the model whose
# domain fits it (the frame by its 640x480 organisation, the scan by its spacing and noise).
run_main_job() {
  local out="$BUILD_DIR/out" bin="$BUILD_DIR/bin"
  mkdir -p "$out"
  local models="$BUILD_DIR/models"
  default_models "$models"
  "$bin/primlabel-synth" --scene table --sensor lms400 --seed 3000 -o "$out/scan.pcd"
  "$bin/primlabel-synth" --scene table --sensor kinect --seed 3000 -o "$out/frame.pcd"

  local log_file="$out/server.log"
  "$bin/primlabel-server" --models "$models" \
    --listen 127.0.0.1:0 --metrics-listen 127.0.0.1:0 --drain-seconds 5 >"$log_file" 2>&1 &
  local server=$!
  trap 'kill "$server" 2>/dev/null || true' EXIT
  local port=""
  for _ in $(seq 1 100); do  # up to 10 s for the model to load and the port to open
    port=$(sed -n 's/.*event=listening.* port=\([0-9]*\).*/\1/p' "$log_file" | head -n1)
    [[ -n "$port" ]] && break
    kill -0 "$server" 2>/dev/null || { cat "$log_file" >&2; return 1; }
    sleep 0.1
  done
  [[ -n "$port" ]] || { log "the server did not start; see $log_file"; return 1; }
  log "primlabel-server serves $BUILD_DIR/models on 127.0.0.1:$port"

  "$bin/primlabel" --server "127.0.0.1:$port" health
  "$bin/primlabel" --server "127.0.0.1:$port" models
  "$bin/primlabel" --server "127.0.0.1:$port" label "$out/scan.pcd" \
    -o "$out/scan_labeled.pcd" --png
  "$bin/primlabel" --server "127.0.0.1:$port" label "$out/frame.pcd" \
    -o "$out/frame_labeled.pcd" --png
  local name
  for name in scan:tabletop-lms400 frame:tabletop-kinect; do
    echo "${name%%:*} (${name#*:}): $("$bin/primlabel-eval" --model \
      "$models/${name#*:}/1/model.plm" -q "$out/${name%%:*}.pcd" | grep -E '^accuracy')" || true
  done
  kill -TERM "$server" && wait "$server" || true
  trap - EXIT
  log "wrote $out/scan_labeled.pcd, $out/frame_labeled.pcd and their PNG renders (labels from the service)"
}

run_tests() {
  ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" --timeout 600
}

case "${1:-}" in
  deps) install_packages ;;
  default-model) install_packages; build; default_models "${2:-}" ;;
  build) install_packages; build ;;
  run) install_packages; build; run_main_job ;;
  test) install_packages; build; run_tests ;;
  kinect-model)
    [[ -n "${2:-}" ]] || { echo "usage: $0 kinect-model OUT [N...]" >&2; exit 2; }
    kinect_real_model "${@:2}" ;;
  *) echo "usage: $0 run|test|build|deps|default-model [DIR]|kinect-model OUT [N...]" >&2; exit 2 ;;
esac
