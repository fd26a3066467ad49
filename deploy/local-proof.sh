#!/usr/bin/env bash
# The local proof of the Compose topology, without Docker, on 127.0.0.1 only: three
# build/bin/primlabel-server processes, Debian's nginx as the gRPC load balancer (config derived
# from deploy/nginx/nginx.conf) and Debian's Prometheus scraping every replica each second with
# deploy/prometheus/alerts.yml loaded. Then it checks:
#
#   (a) primlabel-loadgen, through nginx, reaches every replica: each replica's own /metrics
#       counts Label calls;
#   (b) Prometheus' HTTP query API, once it has scraped every replica after the run, returns
#       sum(primlabel_requests_total{method="Label"}) equal to the calls the load generator made;
#   (c) primlabel-upload, through nginx, loses no scan when one replica is killed (SIGKILL) while
#       it labels one of them: every scan has exactly one labeled output and the spool is empty.
#
#   deploy/local-proof.sh [BUILD_DIR | --build-dir BUILD_DIR] [--hold SECONDS]
#
# BUILD_DIR (default: the repository's build) holds bin/primlabel-server and the other tools.
# --hold keeps the topology up for SECONDS after the checks (the ports are logged).
# Exit status: 0 every check passed, 1 a check failed or the topology did not come up,
# 2 bad usage, 77 nginx, Prometheus or python3 is not installed (CTest reports a skip).
# Every port is a free one picked at run time; everything lives in a temporary directory and every
# process is stopped by the trap, whatever happens (KEEP_WORK=1 keeps the directory).
#
# Environment: BUILD_DIR (build), PRIMLABEL_BIN_DIR (BUILD_DIR/bin), MODELS (a model repository;
#   default: train a small node-only model, ~7 s), LOADGEN_REQUESTS (15), UPLOAD_SCANS (12).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
HOLD_SECONDS=0
REPLICAS=3
VICTIM=2  # the replica killed in check (c)
LOADGEN_REQUESTS=${LOADGEN_REQUESTS:-15}
UPLOAD_SCANS=${UPLOAD_SCANS:-12}
SKIP=77

usage() { sed -n '14p' "${BASH_SOURCE[0]}" | sed 's/^#   /usage: /'; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --build-dir) BUILD_DIR=${2:?--build-dir needs a directory}; shift 2 ;;
    --hold) HOLD_SECONDS=${2:?--hold needs seconds}; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    -*) usage >&2; exit 2 ;;
    *) BUILD_DIR=$1; shift ;;
  esac
done
BIN=${PRIMLABEL_BIN_DIR:-$BUILD_DIR/bin}

STARTED=$SECONDS
log() { echo "[local-proof $((SECONDS - STARTED))s] $*" >&2; }
die() { log "$*"; exit 1; }

NGINX=$(command -v nginx || echo /usr/sbin/nginx)
[[ -x "$NGINX" ]] || { log "SKIP: nginx not installed (apt-get install nginx)"; exit $SKIP; }
PROMETHEUS=$(command -v prometheus || echo /usr/bin/prometheus)
[[ -x "$PROMETHEUS" ]] || { log "SKIP: prometheus not installed (apt-get install prometheus)"; exit $SKIP; }
# Debian's python3 first (a pyenv shim may sit earlier in PATH); only its standard library is used.
PY=/usr/bin/python3
[[ -x "$PY" ]] || PY=$(command -v python3) || { log "SKIP: python3 not installed"; exit $SKIP; }
for tool in primlabel-server primlabel-loadgen primlabel-upload primlabel-synth primlabel-train; do
  [[ -x "$BIN/$tool" ]] || die "$BIN/$tool not built (deploy/setup.sh build)"
done

WORK=$(mktemp -d "${TMPDIR:-/tmp}/primlabel-proof-XXXXXX")
PIDS=()
cleanup() {
  local status=$?
  trap - EXIT INT TERM
  for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  # Bounded: the servers drain for 2 s here, then anything left is killed.
  for _ in $(seq 50); do
    local alive=0
    for pid in "${PIDS[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    [[ $alive -eq 0 ]] && break
    sleep 0.1
  done
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [[ $status -ne 0 && $status -ne $SKIP ]]; then
    log "failed (status $status); last log lines:"
    for f in "$WORK"/*.log "$WORK"/nginx/error.log; do
      [[ -s "$f" ]] && { echo "==> $f" >&2; tail -n 8 "$f" >&2; }
    done
  fi
  if [[ "${KEEP_WORK:-0}" == 1 ]]; then log "kept $WORK"; else rm -rf "$WORK"; fi
  exit "$status"
}
trap cleanup EXIT INT TERM

# Polls `command` (quiet on success and failure alike) every 0.2 s for at most `seconds`.
wait_until() {
  local seconds=$1 what=$2
  shift 2
  for _ in $(seq $((seconds * 5))); do
    "$@" >/dev/null && return 0
    sleep 0.2
  done
  die "timed out after ${seconds}s waiting for $what"
}

# ---- small helpers in Python (standard library only): ports, /metrics, the Prometheus API ----
cat >"$WORK/proof.py" <<'EOF'
import json, os, re, signal, socket, sys, time, urllib.parse, urllib.request

def get(url, timeout=2):
    with urllib.request.urlopen(url, timeout=timeout) as response:
        return response.read().decode()

def metric(url, name, *filters):
    """Sum of the samples of `name` whose labels include every key="value" in filters."""
    total = 0.0
    for line in get(url).splitlines():
        m = re.match(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{([^}]*)\})?\s+(\S+)', line)
        if not m or m.group(1) != name:
            continue
        labels = dict(re.findall(r'(\w+)="((?:[^"\\]|\\.)*)"', m.group(3) or ""))
        if all(labels.get(k) == v for k, v in (f.split("=", 1) for f in filters)):
            total += float(m.group(4))
    return total

def query(port, expr):
    """The value of an instant query whose result has at most one series (none: 'none')."""
    url = "http://127.0.0.1:%s/api/v1/query?query=%s" % (port, urllib.parse.quote(expr))
    body = json.loads(get(url))
    if body.get("status") != "success":
        raise SystemExit("query failed: %s" % body)
    result = body["data"]["result"]
    return result[0]["value"][1] if result else "none"

def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]

def fmt(x):
    return str(int(x)) if float(x).is_integer() else str(x)

cmd, args = sys.argv[1], sys.argv[2:]
if cmd == "free-port":
    print(free_port())
elif cmd == "metric":
    print(fmt(metric(*args)))
elif cmd == "query":
    print(query(*args))
elif cmd == "prom-count-after":
    # Polls until every target was scraped after `since` (epoch s) and the summed Label count
    # equals `expected`; prints the last count and exits 1 when `seconds` pass first.
    port, expected, since, seconds, targets = args[0], float(args[1]), float(args[2]), float(args[3]), int(args[4])
    deadline, count, scraped = time.time() + seconds, "none", 0
    while True:
        try:
            scraped = int(float(query(port, 'count(timestamp(up{job="primlabel"}) > %f)' % since)
                                .replace("none", "0")))
            count = query(port, 'sum(primlabel_requests_total{job="primlabel",method="Label"})')
            if scraped == targets and count != "none" and float(count) == expected:
                print(fmt(count)); sys.exit(0)
        except Exception as e:  # Prometheus busy: try again until the deadline
            count = "error: %s" % e
        if time.time() > deadline:
            print("%s (targets scraped since the run: %d of %d)" % (count, scraped, targets))
            sys.exit(1)
        time.sleep(0.25)
elif cmd == "kill-when-busy":
    # SIGKILLs `pid` as soon as at least `min_done` files are in `out_dir` and its /metrics shows
    # a request in flight; prints "busy" or, when that does not happen within `seconds`, kills it
    # anyway and prints "idle".
    url, pid, out_dir, min_done, seconds = args[0], int(args[1]), args[2], int(args[3]), float(args[4])
    deadline, state = time.time() + seconds, "idle"
    while time.time() < deadline:
        try:
            done = len([f for f in os.listdir(out_dir) if f.endswith(".pcd")])
            if done >= min_done and metric(url, "primlabel_inflight_requests") > 0:
                state = "busy"; break
        except Exception:  # no output directory yet, or a slow /metrics
            pass
        time.sleep(0.03)
    os.kill(pid, signal.SIGKILL)
    print(state)
elif cmd == "loadgen-calls":
    step = json.load(open(args[0]))["steps"][0]
    print(step["ok"], step["errors"])
else:
    raise SystemExit("unknown helper " + cmd)
EOF
helper() { "$PY" "$WORK/proof.py" "$@"; }

# ---- model repository ----
MODELS=${MODELS:-}
if [[ -z "$MODELS" ]]; then
  MODELS=$WORK/models
  mkdir -p "$MODELS/tabletop/1"
  log "training a small node-only model into $MODELS"
  "$BIN/primlabel-train" --synth-train 1 --synth-val 0 --kind node --iterations 30 \
    --name tabletop -q -o "$MODELS/tabletop/1/model.plm" >"$WORK/train.log" 2>&1 ||
    die "primlabel-train failed"
fi

# ---- three replicas, each on ports of its own choosing (port 0), read back from its log ----
GRPC_PORTS=()
METRICS_PORTS=()
SERVER_PIDS=()
for i in $(seq "$REPLICAS"); do
  PRIMLABEL_DRAIN_SECONDS=2 "$BIN/primlabel-server" --models "$MODELS" --listen 127.0.0.1:0 \
    --metrics-listen 127.0.0.1:0 --reload-seconds 0 >"$WORK/server-$i.log" 2>&1 &
  PIDS+=($!)
  SERVER_PIDS+=($!)
done
listening() {
  grep -q 'event=listening' "$WORK/server-$1.log" && return 0
  kill -0 "${SERVER_PIDS[$(($1 - 1))]}" 2>/dev/null || die "replica $1 exited before listening"
  return 1
}
for i in $(seq "$REPLICAS"); do
  wait_until 60 "replica $i to listen" listening "$i"
  line=$(grep -m1 'event=listening' "$WORK/server-$i.log")
  GRPC_PORTS+=("$(sed -E 's/.* port=([0-9]+).*/\1/' <<<"$line")")
  METRICS_PORTS+=("$(sed -E 's/.* metrics_port=([0-9]+).*/\1/' <<<"$line")")
done
metrics_url() { echo "http://127.0.0.1:${METRICS_PORTS[$(($1 - 1))]}/metrics"; }
metrics_up() { helper metric "$(metrics_url "$1")" primlabel_models_loaded >/dev/null 2>&1; }
for i in $(seq "$REPLICAS"); do wait_until 30 "replica $i /metrics" metrics_up "$i"; done
log "$REPLICAS replicas up: gRPC ${GRPC_PORTS[*]}, metrics ${METRICS_PORTS[*]}"

# ---- nginx: the checked-in config, pointed at the local replicas, all paths in $WORK/nginx ----
# A free port can be taken by someone else before nginx binds it: then try another.
mkdir -p "$WORK/nginx"
start_nginx() {
  local port=$1 sed_args
  sed_args=(-e "s|listen 50051 http2;|listen 127.0.0.1:$port http2;|"
            -e "s|^pid .*|pid $WORK/nginx/nginx.pid;|"
            -e "s|access_log /dev/stdout;|access_log $WORK/nginx/access.log;|"
            -e "s|^http {|http {\n  client_body_temp_path $WORK/nginx/body;\n  proxy_temp_path $WORK/nginx/proxy;\n  fastcgi_temp_path $WORK/nginx/fastcgi;\n  uwsgi_temp_path $WORK/nginx/uwsgi;\n  scgi_temp_path $WORK/nginx/scgi;|")
  for i in $(seq "$REPLICAS"); do
    sed_args+=(-e "s|server primlabel-$i:50051|server 127.0.0.1:${GRPC_PORTS[$((i - 1))]}|")
  done
  {
    # As root, nginx would switch its workers to "nobody", who may not enter $WORK's parents.
    [[ $(id -u) -eq 0 ]] && echo "user root;"
    sed "${sed_args[@]}" "$ROOT/deploy/nginx/nginx.conf"
  } >"$WORK/nginx/nginx.conf"
  "$NGINX" -t -q -e stderr -p "$WORK/nginx" -c "$WORK/nginx/nginx.conf" || die "nginx -t failed"
  "$NGINX" -e "$WORK/nginx/error.log" -p "$WORK/nginx" -c "$WORK/nginx/nginx.conf" \
    -g "daemon off;" >"$WORK/nginx.log" 2>&1 &
  NGINX_PID=$!
  for _ in $(seq 50); do
    kill -0 "$NGINX_PID" 2>/dev/null || { wait "$NGINX_PID" || true; return 1; }
    (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && { PIDS+=("$NGINX_PID"); return 0; }
    sleep 0.2
  done
  kill -KILL "$NGINX_PID" 2>/dev/null || true
  return 1
}
PROXY_PORT=
for attempt in 1 2 3; do
  port=$(helper free-port)
  if start_nginx "$port"; then PROXY_PORT=$port; break; fi
  log "nginx did not come up on $port (attempt $attempt)"
done
[[ -n "$PROXY_PORT" ]] || die "nginx did not start"
PROXY=127.0.0.1:$PROXY_PORT
log "nginx gRPC load balancer on $PROXY"

# ---- Prometheus: every replica each second, with the alert rules ----
{
  echo "global: {scrape_interval: 1s, scrape_timeout: 1s, evaluation_interval: 1s}"
  echo "rule_files: ['$ROOT/deploy/prometheus/alerts.yml']"
  echo "scrape_configs:"
  echo "  - job_name: primlabel"
  echo "    static_configs:"
  echo "      - targets:"
  for port in "${METRICS_PORTS[@]}"; do echo "          - 127.0.0.1:$port"; done
} >"$WORK/prometheus.yml"
PROM_PORT=
for attempt in 1 2 3; do
  port=$(helper free-port)
  "$PROMETHEUS" --config.file="$WORK/prometheus.yml" --storage.tsdb.path="$WORK/prometheus" \
    --web.listen-address="127.0.0.1:$port" >"$WORK/prometheus.log" 2>&1 &
  pid=$!
  for _ in $(seq 100); do
    kill -0 "$pid" 2>/dev/null || break
    helper query "$port" 'vector(1)' >/dev/null 2>&1 && { PROM_PORT=$port; break; }
    sleep 0.2
  done
  if [[ -n "$PROM_PORT" ]]; then PIDS+=("$pid"); break; fi
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  log "Prometheus did not come up on $port (attempt $attempt)"
done
[[ -n "$PROM_PORT" ]] || die "Prometheus did not start"
all_targets_up() { [[ $(helper query "$PROM_PORT" 'sum(up{job="primlabel"})' 2>/dev/null) == "$REPLICAS" ]]; }
wait_until 60 "Prometheus to see $REPLICAS targets up" all_targets_up
log "Prometheus on 127.0.0.1:$PROM_PORT scrapes all $REPLICAS replicas"

RESULTS=()
FAILED=0
record() {  # record PASS|FAIL text
  RESULTS+=("$1 $2")
  [[ $1 == PASS ]] || FAILED=1
  log "$1 $2"
}

# ---- (a) + (b): the load generator through nginx ----
log "primlabel-loadgen: $LOADGEN_REQUESTS Label calls through nginx"
set +e
"$BIN/primlabel-loadgen" --server "$PROXY" --synth 3 --max-points 5000 --concurrency 3 \
  --requests "$LOADGEN_REQUESTS" --duration 0 --max-duration 120 --format json \
  >"$WORK/loadgen.json" 2>"$WORK/loadgen.log"
loadgen_status=$?
set -e
RUN_END=$(date +%s.%N)
read -r ok errors < <(helper loadgen-calls "$WORK/loadgen.json" 2>/dev/null || echo "0 0")
sent=$((ok + errors))
if [[ $loadgen_status -eq 0 && $ok -eq $LOADGEN_REQUESTS && $errors -eq 0 ]]; then
  record PASS "loadgen: $ok of $LOADGEN_REQUESTS calls OK through nginx"
else
  record FAIL "loadgen: exit $loadgen_status, $ok OK and $errors failed of $LOADGEN_REQUESTS"
fi

per_replica=()
replica_sum=0
all_served=1
for i in $(seq "$REPLICAS"); do
  n=$(helper metric "$(metrics_url "$i")" primlabel_requests_total method=Label || echo 0)
  per_replica+=("replica$i=$n")
  replica_sum=$((replica_sum + ${n%.*}))
  [[ ${n%.*} -gt 0 ]] || all_served=0
done
if [[ $all_served -eq 1 && $replica_sum -eq $sent ]]; then
  record PASS "(a) every replica served Label calls: ${per_replica[*]} (sum $replica_sum)"
else
  record FAIL "(a) every replica served Label calls: ${per_replica[*]} (sum $replica_sum, loadgen sent $sent)"
fi

if prom=$(helper prom-count-after "$PROM_PORT" "$sent" "$RUN_END" 20 "$REPLICAS"); then
  record PASS "(b) Prometheus sum(primlabel_requests_total{method=\"Label\"}) = $prom = calls the loadgen made"
else
  record FAIL "(b) Prometheus sum(primlabel_requests_total{method=\"Label\"}) = $prom after 20 s, loadgen made $sent"
fi

# ---- (c): uploads through nginx while one replica is killed ----
mkdir -p "$WORK/scans"
for i in $(seq "$UPLOAD_SCANS"); do
  "$BIN/primlabel-synth" --scene table --sensor lms400 --seed $((4000 + i)) --lines 40 -q \
    -o "$WORK/scans/scan-$i.pcd"
done
victim_pid=${SERVER_PIDS[$((VICTIM - 1))]}
log "primlabel-upload: $UPLOAD_SCANS scans through nginx; replica $VICTIM (pid $victim_pid) is killed mid-run"
"$BIN/primlabel-upload" --server "$PROXY" --spool "$WORK/spool" -o "$WORK/out" --workers 2 \
  --backoff-max 1 --timeout 90 --status-interval 0 "$WORK"/scans/*.pcd \
  >"$WORK/upload.out" 2>"$WORK/upload.log" &
upload_pid=$!
PIDS+=("$upload_pid")
disown "$victim_pid"  # its death is expected: no "Killed" notice from bash
kill_state=$(helper kill-when-busy "$(metrics_url "$VICTIM")" "$victim_pid" "$WORK/out" 3 30)
done_at_kill=$(find "$WORK/out" -maxdepth 1 -name '*.pcd' 2>/dev/null | wc -l)
log "replica $VICTIM killed ($kill_state) with $done_at_kill of $UPLOAD_SCANS scans labeled"
upload_status=
for _ in $(seq 1000); do  # at most 100 s; the uploader gives up after --timeout 90
  if ! kill -0 "$upload_pid" 2>/dev/null; then
    set +e; wait "$upload_pid"; upload_status=$?; set -e
    break
  fi
  sleep 0.1
done
[[ -n "$upload_status" ]] || { kill -KILL "$upload_pid" 2>/dev/null || true; upload_status=timeout; }

missing=()
mismatched=()
for scan in "$WORK"/scans/*.pcd; do
  # Outputs are named after their scan file: <stem>.<key>.pcd, one per scan.
  stem=$(basename "$scan" .pcd)
  found=("$WORK/out/$stem".*.pcd)
  out=${found[0]}
  if [[ ${#found[@]} -ne 1 || ! -f "$out" ]]; then
    missing+=("$(basename "$scan")")
  elif [[ $(grep -a -m1 '^POINTS' "$scan") != $(grep -a -m1 '^POINTS' "$out") ]]; then
    mismatched+=("$(basename "$scan")")
  fi
done
# Every labeled cloud has its .classes.json beside it; anything else in out/ is an extra output.
outputs=$(find "$WORK/out" -mindepth 1 ! -name '*.classes.json' | wc -l)
sidecars=$(find "$WORK/out" -mindepth 1 -name '*.classes.json' | wc -l)
spooled=$(find "$WORK/spool" -type f 2>/dev/null | wc -l)
retries=$(grep -o 'retries [0-9]*' "$WORK/upload.log" | tail -1 | cut -d' ' -f2)
# Calls nginx could not complete (the killed replica's in-flight call: 502, which gRPC clients
# read as UNAVAILABLE and retry).
failed_calls=$(grep -c '" 50[0-9] ' "$WORK/nginx/access.log" || true)
detail="exit $upload_status, $outputs outputs ($sidecars classes.json) for $UPLOAD_SCANS scans, ${#missing[@]} missing, ${#mismatched[@]} with other point counts, $spooled files left in the spool; replica $VICTIM killed while $kill_state with $done_at_kill scans done; nginx failed $failed_calls call(s), retried by the client (uploader backoff retries: ${retries:-?})"
if [[ $upload_status == 0 && ${#missing[@]} -eq 0 && ${#mismatched[@]} -eq 0 && $outputs -eq $UPLOAD_SCANS && $sidecars -eq $UPLOAD_SCANS &&
      $spooled -eq 0 && $kill_state == busy && $done_at_kill -lt $UPLOAD_SCANS ]]; then
  record PASS "(c) no scan lost when a replica dies mid-upload: $detail"
else
  [[ ${#missing[@]} -eq 0 ]] || log "missing outputs for: ${missing[*]}"
  record FAIL "(c) no scan lost when a replica dies mid-upload: $detail"
fi

# ---- summary ----
echo "local proof ($REPLICAS replicas, nginx $PROXY, Prometheus 127.0.0.1:$PROM_PORT, $((SECONDS - STARTED)) s):"
for r in "${RESULTS[@]}"; do echo "  $r"; done
if [[ "$HOLD_SECONDS" -gt 0 ]]; then
  log "holding for ${HOLD_SECONDS}s (Ctrl-C stops everything)"
  sleep "$HOLD_SECONDS"
fi
if [[ $FAILED -ne 0 ]]; then
  echo "local proof: FAIL"
  exit 1
fi
echo "local proof: PASS"
