#!/usr/bin/env bash
# The Compose topology without Docker, on 127.0.0.1 only: three build/bin/primlabel-server
# processes, Debian's nginx as the gRPC proxy (config derived from deploy/nginx/nginx.conf) and
# Prometheus scraping every replica each second with deploy/prometheus/alerts.yml loaded.
# Everything lives in a temporary directory and is stopped by the trap, whatever happens.
#
#   deploy/local-proof.sh [--hold SECONDS]
#
# Environment: BUILD_DIR (build), PRIMLABEL_SERVER (default: BUILD_DIR/bin/primlabel-server),
#   MODELS (a model repository; default: make one with deploy/make-default-model.sh),
#   PORT_BASE (15050: proxy PORT_BASE, replicas +1..+3, their metrics +101..+103, Prometheus +90).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
PORT_BASE=${PORT_BASE:-15050}
HOLD_SECONDS=0
REPLICAS=3
if [[ "${1:-}" == "--hold" ]]; then HOLD_SECONDS=${2:?--hold needs seconds}; fi

log() { echo "[local-proof] $*" >&2; }
die() { log "$*"; exit 1; }

SERVER=${PRIMLABEL_SERVER:-$BUILD_DIR/bin/primlabel-server}
[[ -x "$SERVER" ]] || die "$SERVER not built (deploy/setup.sh build)"
NGINX=$(command -v nginx || echo /usr/sbin/nginx)
[[ -x "$NGINX" ]] || die "nginx not installed (apt-get install nginx)"
command -v prometheus >/dev/null || die "prometheus not installed (apt-get install prometheus)"
command -v curl >/dev/null || die "curl not installed"

WORK=$(mktemp -d -t primlabel-proof-XXXXXX)
PIDS=()
cleanup() {
  local status=$?
  trap - EXIT INT TERM
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  # Bounded: the servers drain for PRIMLABEL_DRAIN_SECONDS (2 here), then anything left is killed.
  for _ in $(seq 50); do
    local alive=0
    for pid in "${PIDS[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    [[ $alive -eq 0 ]] && break
    sleep 0.1
  done
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [[ $status -ne 0 ]]; then
    log "failed; last log lines:"
    tail -n 5 "$WORK"/*.log >&2 2>/dev/null || true
  fi
  rm -rf "$WORK"
  exit "$status"
}
trap cleanup EXIT INT TERM

# Polls `command` every 0.2 s for at most `seconds`.
wait_until() {
  local seconds=$1 what=$2
  shift 2
  for _ in $(seq $((seconds * 5))); do
    "$@" >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  die "timed out after ${seconds}s waiting for $what"
}

# ---- model repository ----
MODELS=${MODELS:-}
if [[ -z "$MODELS" ]]; then
  MODELS=$WORK/models
  log "making the default model in $MODELS"
  "$ROOT/deploy/make-default-model.sh" "$MODELS" >"$WORK/model.log" 2>&1
fi

# ---- three replicas ----
for i in $(seq "$REPLICAS"); do
  grpc=$((PORT_BASE + i))
  metrics=$((PORT_BASE + 100 + i))
  PRIMLABEL_DRAIN_SECONDS=2 "$SERVER" --models "$MODELS" --listen "127.0.0.1:$grpc" \
    --metrics-listen "127.0.0.1:$metrics" >"$WORK/server-$i.log" 2>&1 &
  PIDS+=($!)
done
for i in $(seq "$REPLICAS"); do
  wait_until 60 "replica $i /metrics" curl -fsS "http://127.0.0.1:$((PORT_BASE + 100 + i))/metrics"
done
log "$REPLICAS replicas up on 127.0.0.1:$((PORT_BASE + 1))-$((PORT_BASE + REPLICAS))"

# ---- nginx: the checked-in config, pointed at the local replicas, all paths in $WORK ----
mkdir -p "$WORK/nginx"
sed_args=(-e "s|listen 50051 http2;|listen 127.0.0.1:$PORT_BASE http2;|"
          -e "s|^pid .*|pid $WORK/nginx/nginx.pid;|"
          -e "s|access_log /dev/stdout;|access_log $WORK/nginx/access.log;|"
          -e "s|^http {|http {\n  client_body_temp_path $WORK/nginx/body;\n  proxy_temp_path $WORK/nginx/proxy;\n  fastcgi_temp_path $WORK/nginx/fastcgi;\n  uwsgi_temp_path $WORK/nginx/uwsgi;\n  scgi_temp_path $WORK/nginx/scgi;|")
for i in $(seq "$REPLICAS"); do
  sed_args+=(-e "s|server primlabel-$i:50051|server 127.0.0.1:$((PORT_BASE + i))|")
done
{
  # As root, nginx would switch its workers to "nobody", who cannot enter $WORK.
  [[ $(id -u) -eq 0 ]] && echo "user root;"
  sed "${sed_args[@]}" "$ROOT/deploy/nginx/nginx.conf"
} >"$WORK/nginx/nginx.conf"
"$NGINX" -t -q -e stderr -p "$WORK/nginx" -c "$WORK/nginx/nginx.conf"
"$NGINX" -e "$WORK/nginx/error.log" -p "$WORK/nginx" -c "$WORK/nginx/nginx.conf" \
  -g "daemon off;" >"$WORK/nginx.log" 2>&1 &
PIDS+=($!)
wait_until 10 "nginx on $PORT_BASE" bash -c "exec 3<>/dev/tcp/127.0.0.1/$PORT_BASE"
log "nginx gRPC proxy on 127.0.0.1:$PORT_BASE"

# ---- Prometheus: every replica each second, with the alert rules ----
PROM_PORT=$((PORT_BASE + 90))
{
  echo "global: {scrape_interval: 1s, evaluation_interval: 1s}"
  echo "rule_files: ['$ROOT/deploy/prometheus/alerts.yml']"
  echo "scrape_configs:"
  echo "  - job_name: primlabel"
  echo "    static_configs:"
  echo "      - targets:"
  for i in $(seq "$REPLICAS"); do echo "          - 127.0.0.1:$((PORT_BASE + 100 + i))"; done
} >"$WORK/prometheus.yml"
prometheus --config.file="$WORK/prometheus.yml" --storage.tsdb.path="$WORK/prometheus" \
  --web.listen-address="127.0.0.1:$PROM_PORT" >"$WORK/prometheus.log" 2>&1 &
PIDS+=($!)
up_count() {
  curl -fsS "http://127.0.0.1:$PROM_PORT/api/v1/query?query=sum(up%7Bjob%3D%22primlabel%22%7D)" |
    python3 -c 'import json,sys; r=json.load(sys.stdin)["data"]["result"]; print(int(float(r[0]["value"][1])) if r else 0)'
}
all_targets_up() { [[ $(up_count) -eq $REPLICAS ]]; }
wait_until 60 "Prometheus to see $REPLICAS targets up" all_targets_up
log "Prometheus on 127.0.0.1:$PROM_PORT scrapes all $REPLICAS replicas"

# The load generator (build/bin/primlabel-loadgen) comes later; it will run here against
# 127.0.0.1:$PORT_BASE and compare its counts with primlabel_requests_total.
if [[ "$HOLD_SECONDS" -gt 0 ]]; then
  log "holding for ${HOLD_SECONDS}s (Ctrl-C stops everything)"
  sleep "$HOLD_SECONDS"
fi
log "ok"
