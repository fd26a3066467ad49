#!/usr/bin/env bash
# Held-out robustness sweep (opt-in, not part of CTest): labels held-out synthetic scenes (test
# seeds 3000.., never trained or validated on) at several range-noise scales and densities with
# each model, and prints accuracy and per-class recall per condition.
#
#   tools/robustness_sweep.sh BUILD_DIR MODEL.plm [MODEL.plm ...]
#
# Environment: SCENES (4 test scenes), SENSOR (lms400), NOISE ("1 2 3 4": noise scales at full
# density), DENSITY ("0.5 0.35 0.25": shares kept at 1x noise), THREADS (all cores), WORK (a
# temporary directory; the scenes are kept there and reused when WORK is given).
# A few minutes for two models on 2 cores: scenes are generated once, each model labels them once.
set -euo pipefail

if [[ $# -lt 2 ]]; then
  echo "usage: $0 BUILD_DIR MODEL.plm [MODEL.plm ...]" >&2
  exit 2
fi
BUILD_DIR=$1
shift
MODELS=("$@")
BIN=$BUILD_DIR/bin
SCENES=${SCENES:-4}
SENSOR=${SENSOR:-lms400}
NOISE=${NOISE:-1 2 3 4}
DENSITY=${DENSITY:-0.5 0.35 0.25}
THREADS_ARG=()
[[ -n "${THREADS:-}" ]] && THREADS_ARG=(--threads "$THREADS")
for m in "${MODELS[@]}"; do
  [[ -f "$m" ]] || { echo "$0: no model file $m" >&2; exit 2; }
done
[[ -x "$BIN/primlabel-synth" && -x "$BIN/primlabel-eval" ]] ||
  { echo "$0: build primlabel-synth and primlabel-eval in $BUILD_DIR first" >&2; exit 1; }
if [[ -z "${WORK:-}" ]]; then
  WORK=$(mktemp -d)
  trap 'rm -rf "$WORK"' EXIT
fi
mkdir -p "$WORK"

# Conditions: "name noise keep".
CONDITIONS=()
for n in $NOISE; do CONDITIONS+=("noise${n}x $n 1"); done
for d in $DENSITY; do CONDITIONS+=("density$(awk "BEGIN{print int($d*100+0.5)}")% 1 $d"); done

for c in "${CONDITIONS[@]}"; do
  read -r name noise keep <<<"$c"
  for i in $(seq 0 $((SCENES - 1))); do
    out="$WORK/$name-$((3000 + i)).pcd"
    [[ -f "$out" ]] || "$BIN/primlabel-synth" --scene table --sensor "$SENSOR" --seed $((3000 + i)) \
      --noise-scale "$noise" --keep "$keep" -q -o "$out"
  done
done

for m in "${MODELS[@]}"; do
  for c in "${CONDITIONS[@]}"; do
    read -r name _ _ <<<"$c"
    "$BIN/primlabel-eval" --model "$m" --json -q "${THREADS_ARG[@]}" "$WORK/$name"-*.pcd \
      >"$WORK/$(basename "$m" .plm).$name.jsonl"
  done
done

# Sum the confusion matrices of a condition's scenes; accuracy and recall per class over them.
python3 - "$WORK" "${MODELS[@]}" -- "${CONDITIONS[@]}" <<'EOF'
import json, os, sys
work = sys.argv[1]
split = sys.argv.index("--")
models, conditions = sys.argv[2:split], [c.split()[0] for c in sys.argv[split + 1:]]
for model in models:
    tag = os.path.basename(model)[:-4] if model.endswith(".plm") else os.path.basename(model)
    rows, names = [], None
    for cond in conditions:
        total = correct = 0
        support, hits = {}, {}
        for line in open(os.path.join(work, f"{tag}.{cond}.jsonl")):
            r = json.loads(line)
            names = list(r["classes"].keys())
            for t, row in enumerate(r["confusion"]):
                n = names[t]
                support[n] = support.get(n, 0) + sum(row)
                hits[n] = hits.get(n, 0) + row[t]
                total += sum(row)
                correct += row[t]
        rows.append((cond, correct / total, {n: hits[n] / support[n] for n in names if support[n]}))
    short = [n.replace("cylinder", "cyl").replace("sphere", "sph").replace("torus", "tor")
             .replace("-convex", "+").replace("-concave", "-") for n in names]
    print(f"model {model}")
    print(f"{'condition':<13} {'accuracy':>8} {'min recall':>10}  " + " ".join(f"{s:>7}" for s in short))
    for cond, acc, rec in rows:
        worst = min(rec.values())
        print(f"{cond:<13} {100 * acc:7.2f}% {worst:10.3f}  " +
              " ".join(f"{rec[n]:7.3f}" if n in rec else f"{'-':>7}" for n in names))
    print()
EOF
