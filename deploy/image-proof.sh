#!/usr/bin/env bash
# The proof that deploy/Dockerfile builds and runs, with Debian's podman and no registry:
#
#   1. base: a Debian 12 (bookworm) minbase made by debootstrap from the Debian mirror, imported
#      into podman as debian:12 (cached: made once, then reused);
#   2. build: `podman build --format docker` of deploy/Dockerfile from the repository root (the
#      docker format keeps the HEALTHCHECK, which OCI drops); checks the image's user, ports,
#      healthcheck and entrypoint, and prints its size (--no-build checks an IMAGE built before);
#   3. run: primlabel-server from the image on 127.0.0.1 with free ports (`podman run` where the
#      sandbox allows containers, else the image's exported root filesystem under chroot, as the
#      image's user 10001 with the image's environment);
#   4. checks, with the image's own primlabel: `health` (the HEALTHCHECK's command) is SERVING,
#      `label` of bun0.pcd returns every point labeled, /metrics has primlabel_ series and counts
#      the Label call, and SIGTERM stops the server cleanly;
#   5. compose: the nginx and Prometheus images of deploy/compose.yaml build and hold Debian's
#      nginx 1.22 and Prometheus 2.42, the versions deploy/local-proof.sh runs (--no-compose skips).
#
#   deploy/image-proof.sh [--no-compose] [--rebuild-base] [--no-build]
#
# About 20-25 minutes on 2 cores the first time (the build stage compiles the server and trains
# the default models); later runs reuse podman's layer cache while the sources are unchanged.
# Exit status: 0 every check passed, 1 a check failed, 2 bad usage, 77 not root or podman,
# debootstrap, chroot or curl missing (PRIMLABEL_IMAGE_PROOF=1 deploy/setup.sh deps installs them).
# The trap stops the server and removes the container, mounts and the temporary directory
# whatever happens (KEEP_WORK=1 keeps the directory); the images are kept (primlabel:proof).
#
# Environment: IMAGE_PROOF_CACHE (/var/tmp/primlabel-image-proof: the base tarball),
#   DEBIAN_MIRROR (http://deb.debian.org/debian), IMAGE (localhost/primlabel:proof),
#   SAMPLE (/work/shared/data/pcl/bun0.pcd, else tests/data/samples/bun0.pcd), PODMAN (podman).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
CACHE=${IMAGE_PROOF_CACHE:-/var/tmp/primlabel-image-proof}
MIRROR=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
IMAGE=${IMAGE:-localhost/primlabel:proof}
BASE=localhost/debian:12
PODMAN=${PODMAN:-podman}
SAMPLE=${SAMPLE:-/work/shared/data/pcl/bun0.pcd}
[[ -f "$SAMPLE" ]] || SAMPLE=$ROOT/tests/data/samples/bun0.pcd
COMPOSE=1
REBUILD_BASE=0
BUILD=1
SKIP=77

usage() { sed -n '18p' "${BASH_SOURCE[0]}" | sed 's/^#   /usage: /'; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --no-compose) COMPOSE=0; shift ;;
    --rebuild-base) REBUILD_BASE=1; shift ;;
    --no-build) BUILD=0; shift ;;
    -h | --help) usage; exit 0 ;;
    *) usage >&2; exit 2 ;;
  esac
done

STARTED=$SECONDS
log() { echo "[image-proof $((SECONDS - STARTED))s] $*" >&2; }
FAILED=0
pass() { log "PASS $*"; }
fail() { log "FAIL $*"; FAILED=1; }
die() { log "FAIL $*"; exit 1; }

[[ $(id -u) -eq 0 ]] || { log "SKIP: must run as root (debootstrap, chroot, podman storage)"; exit $SKIP; }
for tool in "$PODMAN" debootstrap chroot curl; do
  command -v "$tool" >/dev/null || {
    log "SKIP: $tool not installed (PRIMLABEL_IMAGE_PROOF=1 deploy/setup.sh deps)"
    exit $SKIP
  }
done

WORK=$(mktemp -d "${TMPDIR:-/tmp}/primlabel-image-proof-XXXXXX")
ROOTFS=$WORK/rootfs
CONTAINER=primlabel-proof-$$
SERVER_PID=""
MOUNTS=()
cleanup() {
  local status=$?
  trap - EXIT INT TERM
  if [[ -n "$SERVER_PID" ]]; then
    kill -TERM "$SERVER_PID" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$SERVER_PID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$SERVER_PID" 2>/dev/null || true
    wait "$SERVER_PID" 2>/dev/null || true
  fi
  "$PODMAN" rm -f -t 5 "$CONTAINER" >/dev/null 2>&1 || true
  local i
  for ((i = ${#MOUNTS[@]} - 1; i >= 0; i--)); do umount -l "${MOUNTS[i]}" 2>/dev/null || true; done
  if [[ $status -ne 0 && $status -ne $SKIP ]]; then
    log "failed (status $status); last log lines:"
    for f in "$WORK"/*.log; do [[ -s "$f" ]] && { echo "==> $f" >&2; tail -n 15 "$f" >&2; }; done
  fi
  if [[ "${KEEP_WORK:-0}" == 1 ]]; then log "kept $WORK"; else rm -rf "$WORK"; fi
  exit "$status"
}
trap cleanup EXIT INT TERM

free_port() {
  /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'
}

# ---- 1. the base: debootstrapped bookworm, imported as debian:12 ----
make_base_tarball() {
  local tree=$CACHE/rootfs-tmp
  rm -rf "$tree"
  mkdir -p "$CACHE"
  log "debootstrap bookworm (minbase) from $MIRROR"
  debootstrap --variant=minbase bookworm "$tree" "$MIRROR" >"$WORK/debootstrap.log" 2>&1 ||
    die "debootstrap failed"
  # The same apt sources as Debian's own debian:12 image: main, updates and security.
  rm -f "$tree/etc/apt/sources.list" "$tree"/var/cache/apt/archives/*.deb
  cat >"$tree/etc/apt/sources.list.d/debian.sources" <<EOF
Types: deb
URIs: $MIRROR
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: http://deb.debian.org/debian-security
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
  tar -C "$tree" --numeric-owner -cf "$CACHE/bookworm-minbase.tar.tmp" .
  mv "$CACHE/bookworm-minbase.tar.tmp" "$CACHE/bookworm-minbase.tar"
}
if [[ $REBUILD_BASE -eq 1 ]]; then
  rm -f "$CACHE/bookworm-minbase.tar"
  "$PODMAN" rmi -f "$BASE" >/dev/null 2>&1 || true
fi
if ! "$PODMAN" image exists "$BASE"; then
  [[ -f "$CACHE/bookworm-minbase.tar" ]] || make_base_tarball
  "$PODMAN" import --change 'CMD ["bash"]' \
    --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
    "$CACHE/bookworm-minbase.tar" "$BASE" >/dev/null
fi
pass "base $BASE: Debian $(tar -xOf "$CACHE/bookworm-minbase.tar" ./etc/debian_version 2>/dev/null || echo '?') (debootstrap minbase)"

# Containers where the sandbox allows them; otherwise RUN steps use chroot isolation and the
# server runs from the exported root filesystem.
CAN_RUN=0
"$PODMAN" run --rm --pull=never --network host "$BASE" true >/dev/null 2>"$WORK/probe.log" && CAN_RUN=1
ISOLATION=(--isolation chroot)
[[ $CAN_RUN -eq 1 ]] && ISOLATION=()
log "containers: $([[ $CAN_RUN -eq 1 ]] && echo allowed || echo "refused ($(tail -n1 "$WORK/probe.log")); chroot instead")"

# ---- 2. the image ----
build_image() {  # TAG CONTEXT DOCKERFILE
  log "podman build --format docker -t $1 -f $3 $2 (log: $WORK/build-${1##*/}.log)"
  "$PODMAN" build --format docker --pull=never "${ISOLATION[@]}" --network host \
    -f "$3" -t "$1" "$2" >"$WORK/build-${1##*/}.log" 2>&1
}
if [[ $BUILD -eq 1 ]]; then
  build_started=$SECONDS
  build_image "$IMAGE" "$ROOT" "$ROOT/deploy/Dockerfile" || die "the image did not build"
  pass "built $IMAGE in $((SECONDS - build_started)) s ($(grep -c 'Using cache' "$WORK/build-${IMAGE##*/}.log" || true) cached steps)"
else
  "$PODMAN" image exists "$IMAGE" || die "--no-build: no image $IMAGE"
  log "--no-build: checking $IMAGE as it is"
fi

inspect() { "$PODMAN" image inspect --format "$1" "$IMAGE"; }
size=$(inspect '{{.Size}}')
log "image size: $((size / 1000000)) MB"
user=$(inspect '{{.Config.User}}')
[[ "$user" == 10001:10001 ]] && pass "runs as $user" || fail "runs as '$user', not 10001:10001"
health=$(inspect '{{json .HealthCheck}}')
[[ "$health" == *primlabel*health* ]] && pass "HEALTHCHECK kept: $health" ||
  fail "no HEALTHCHECK in the image (built without --format docker?): $health"
ports=$(inspect '{{json .Config.ExposedPorts}}')
[[ "$ports" == *50051* && "$ports" == *9464* ]] && pass "exposes $ports" || fail "exposes $ports"
entrypoint=$(inspect '{{json .Config.Entrypoint}}')
[[ "$entrypoint" == *primlabel-server* ]] || fail "entrypoint $entrypoint"

# The image's files, for its own primlabel client (and for the server where containers are refused).
mkdir -p "$ROOTFS"
cid=$("$PODMAN" create --pull=never "$IMAGE")
"$PODMAN" export "$cid" | tar -C "$ROOTFS" -x
chmod 755 "$ROOTFS"
"$PODMAN" rm "$cid" >/dev/null
[[ ! -e "$ROOTFS/src" ]] && pass "no build tree in the runtime image" || fail "/src in the runtime image"
mount -t proc proc "$ROOTFS/proc" && MOUNTS+=("$ROOTFS/proc")
mount --bind /dev "$ROOTFS/dev" && MOUNTS+=("$ROOTFS/dev")
mapfile -t IMAGE_ENV < <(inspect '{{range .Config.Env}}{{println .}}{{end}}' | sed '/^$/d')
in_image() {  # CMD...: runs CMD from the image's files, as its user, with its environment
  chroot --userspec=10001:10001 "$ROOTFS" /usr/bin/env -i "${IMAGE_ENV[@]}" HOME=/tmp "$@"
}

# ---- 3. the server from the image ----
GRPC_PORT=$(free_port)
METRICS_PORT=$(free_port)
RUN_ENV=(PRIMLABEL_LISTEN=127.0.0.1:$GRPC_PORT PRIMLABEL_METRICS_LISTEN=127.0.0.1:$METRICS_PORT
  PRIMLABEL_DRAIN_SECONDS=2)
if [[ $CAN_RUN -eq 1 ]]; then
  "$PODMAN" run -d --name "$CONTAINER" --network host "${RUN_ENV[@]/#/--env=}" "$IMAGE" >/dev/null
  "$PODMAN" logs -f "$CONTAINER" >"$WORK/server.log" 2>&1 &
  how="podman run --network host"
else
  # A simple command, not the function: $! must be the server itself (chroot and env exec it).
  chroot --userspec=10001:10001 "$ROOTFS" /usr/bin/env -i "${IMAGE_ENV[@]}" HOME=/tmp \
    "${RUN_ENV[@]}" primlabel-server >"$WORK/server.log" 2>&1 &
  SERVER_PID=$!
  how="chroot into the image's root filesystem as 10001:10001"
fi
log "primlabel-server from the image ($how) on 127.0.0.1:$GRPC_PORT, metrics :$METRICS_PORT"

# ---- 4. the checks, with the image's own client ----
client() { in_image primlabel --server "127.0.0.1:$GRPC_PORT" "$@"; }
healthy=0
for _ in $(seq 120); do  # up to 60 s for the default models to load
  if client health >"$WORK/health.log" 2>&1; then healthy=1; break; fi
  [[ -z "$SERVER_PID" ]] || kill -0 "$SERVER_PID" 2>/dev/null || break
  sleep 0.5
done
[[ $healthy -eq 1 ]] || die "the server never reported healthy"
pass "health (the HEALTHCHECK's command): $(tr '\n' ' ' <"$WORK/health.log")"
if [[ $CAN_RUN -eq 1 ]]; then
  "$PODMAN" healthcheck run "$CONTAINER" && pass "podman healthcheck run" || fail "podman healthcheck run"
fi

cp "$SAMPLE" "$ROOTFS/tmp/sample.pcd"
chmod 644 "$ROOTFS/tmp/sample.pcd"
if client label /tmp/sample.pcd -o /tmp/sample_labeled.pcd >"$WORK/label.log" 2>&1; then
  header() { sed -n "s/^$1 //p" "$2" | head -n1; }
  points_in=$(header POINTS "$SAMPLE")
  points_out=$(header POINTS "$ROOTFS/tmp/sample_labeled.pcd")
  fields=$(header FIELDS "$ROOTFS/tmp/sample_labeled.pcd")
  if [[ -n "$points_in" && "$points_in" == "$points_out" && " $fields " == *" label "* ]]; then
    pass "labeled $(basename "$SAMPLE"): $points_out of $points_in points, fields $fields"
  else
    fail "labeled output has POINTS '$points_out' (input '$points_in'), FIELDS '$fields'"
  fi
else
  fail "primlabel label $(basename "$SAMPLE"): $(tail -n3 "$WORK/label.log")"
fi

metrics=$(curl -fsS --max-time 5 "http://127.0.0.1:$METRICS_PORT/metrics" || true)
series=$(grep -c '^primlabel_' <<<"$metrics" || true)
labels=$(awk '/^primlabel_requests_total\{/ && /method="Label"/ { n += $NF } END { print n + 0 }' <<<"$metrics")
if [[ $series -gt 0 && $labels -ge 1 ]]; then
  pass "/metrics: $series primlabel_ samples, primlabel_requests_total{method=\"Label\"} = $labels"
else
  fail "/metrics: $series primlabel_ samples, Label calls counted: $labels"
fi

# SIGTERM: the server drains (2 s here) and exits 0.
if [[ $CAN_RUN -eq 1 ]]; then
  "$PODMAN" stop -t 30 "$CONTAINER" >/dev/null
  code=$("$PODMAN" inspect --format '{{.State.ExitCode}}' "$CONTAINER")
else
  kill -TERM "$SERVER_PID"
  code=0
  wait "$SERVER_PID" || code=$?
  SERVER_PID=""
fi
if [[ $code -eq 0 ]] && grep -q 'event=signal' "$WORK/server.log"; then
  pass "SIGTERM: the server drained and exited 0"
else
  fail "SIGTERM: exit $code, $(grep -c 'event=signal' "$WORK/server.log" || true) signal events logged"
fi

# ---- 5. compose's nginx and Prometheus: Debian's versions, the ones the local proof runs ----
if [[ $COMPOSE -eq 1 ]]; then
  for spec in nginx:primlabel-nginx:1.22-bookworm:1.22 prometheus:primlabel-prometheus:2.42-bookworm:2.42; do
    IFS=: read -r package name tag want <<<"$spec"
    if build_image "localhost/$name:$tag" "$ROOT/deploy/$package" "$ROOT/deploy/$package/Dockerfile"; then
      mnt=$("$PODMAN" image mount "localhost/$name:$tag")
      version=$(dpkg-query --admindir="$mnt/var/lib/dpkg" -W -f '${Version}' "$package" 2>/dev/null || true)
      "$PODMAN" image unmount "localhost/$name:$tag" >/dev/null || true
      host=$(dpkg-query -W -f '${Version}' "$package" 2>/dev/null || echo "not installed")
      [[ "$version" == "$want".* ]] &&
        pass "compose $package image holds Debian's $package $version (the local proof's: $host)" ||
        fail "compose $package image holds $package '$version', want $want.*"
    else
      fail "the compose $package image did not build"
    fi
  done
fi

if [[ $FAILED -eq 0 ]]; then
  log "image proof passed: $IMAGE, $((size / 1000000)) MB, $((SECONDS - STARTED)) s, $(date -u '+%F %H:%M UTC')"
  exit 0
fi
log "image proof FAILED"
exit 1
