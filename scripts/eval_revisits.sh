#!/usr/bin/env bash
# Storage per revisit: each scene is rendered twice with nothing changed in between (objmap_sim
# --revisit with no removed, moved or added object), both sessions are mapped into one map folder (objmap map --map), and the growth
# of map.db over session 2 is compared with the first session's size, with revisit thinning
# (the default) and without it (thinning.enabled=false). Also: the keyframes of session 2 kept
# as revisits, the changes the map reports (every one is false: nothing changed) and the
# inventory's precision and recall against the scene's truth in both maps.
#   bash scripts/eval_revisits.sh [OUT_DIR]
# Environment (defaults in brackets):
#   OBJMAP_EVAL_KINDS   [desk office kitchen lab]
#   OBJMAP_EVAL_SEEDS   [41 42]    (the project's tests use seeds 1 to 4)
#   OBJMAP_EVAL_FRAMES  [300]      frames per session
#   OBJMAP_EVAL_POSES   [input]    input: the sequences' poses; estimate: objmap's own tracking
#   OBJMAP_EVAL_PATH    [patrol]   patrol: session 2 drives session 1's path again, a few cm
#                                  and degrees to one side (objmap_sim --patrol); sweep: it starts
#                                  elsewhere, farther back and higher, and swings across the room
#   OBJMAP_JOBS         [number of cores]   scenes at once
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"
readonly OUT="${1:-${ROOT}/out/eval-revisits}"
readonly KINDS="${OBJMAP_EVAL_KINDS:-desk office kitchen lab}"
readonly SEEDS="${OBJMAP_EVAL_SEEDS:-41 42}"
readonly FRAMES="${OBJMAP_EVAL_FRAMES:-300}"
readonly POSES="${OBJMAP_EVAL_POSES:-input}"
readonly PATH_KIND="${OBJMAP_EVAL_PATH:-patrol}"
readonly JOBS="${OBJMAP_JOBS:-$(nproc)}"
readonly SIM="${BUILD_DIR}/tests/sim/objmap_sim"
readonly CLI="${BUILD_DIR}/client/cli/objmap"

for tool in "${SIM}" "${CLI}"; do
  if [[ ! -x "${tool}" ]]; then
    echo "eval_revisits: ${tool} is missing: build first (bash scripts/setup.sh)" >&2
    exit 1
  fi
done
case "${PATH_KIND}" in patrol | sweep) ;; *)
  echo "eval_revisits: OBJMAP_EVAL_PATH must be patrol or sweep, not ${PATH_KIND}" >&2
  exit 2
  ;;
esac
case "${POSES}" in input | estimate) ;; *)
  echo "eval_revisits: OBJMAP_EVAL_POSES must be input or estimate, not ${POSES}" >&2
  exit 2
  ;;
esac
mkdir -p "${OUT}"

# map.db after the mapping process ended (its write-ahead log folded in), bytes.
db_bytes() { stat -c %s "$1/map.db"; }

run_scene() {
  local kind="$1" seed="$2"
  local first="${OUT}/${kind}-${seed}-a" second="${OUT}/${kind}-${seed}-same-${PATH_KIND}"
  local patrol=""
  [[ "${PATH_KIND}" == patrol ]] && patrol="--patrol"
  if [[ ! -f "${second}/changes.json" ]]; then
    # shellcheck disable=SC2086
    "${SIM}" --out "${first}" --kind "${kind}" --seed "${seed}" --frames "${FRAMES}" \
      --revisit "${second}" --removed 0 --moved 0 --added 0 ${patrol} \
      >"${OUT}/${kind}-${seed}-${PATH_KIND}.sim.log" 2>&1
  fi
  local thinning
  for thinning in true false; do
    local map="${OUT}/${kind}-${seed}-${PATH_KIND}-${POSES}-thinning-${thinning}"
    rm -rf "${map}" "${map}.log" "${map}.bytes"
    "${CLI}" map "${first}" --detections "${first}/detections.json" --poses "${POSES}" \
      --map "${map}" --set "thinning.enabled=${thinning}" >>"${map}.log" 2>&1
    db_bytes "${map}" >"${map}.bytes"
    "${CLI}" map "${second}" --detections "${second}/detections.json" --poses "${POSES}" \
      --map "${map}" --set "thinning.enabled=${thinning}" >>"${map}.log" 2>&1
    db_bytes "${map}" >>"${map}.bytes"
    "${CLI}" eval "${map}" --changes "${second}/changes.json" --gt "${second}/ground_truth.json" \
      --gt-before "${first}/ground_truth.json" --since-session 2 --json >"${map}.eval.json" \
      2>/dev/null
  done
}

pids=()
for kind in ${KINDS}; do
  for seed in ${SEEDS}; do
    run_scene "${kind}" "${seed}" &
    pids+=($!)
    while (($(jobs -rp | wc -l) >= JOBS)); do sleep 1; done
  done
done
failed=0
for pid in "${pids[@]}"; do wait "${pid}" || failed=1; done
if ((failed)); then
  echo "eval_revisits: a scene failed; its logs are in ${OUT}" >&2
  exit 1
fi

/usr/bin/python3 - "${OUT}" "${POSES}" "${KINDS}" "${SEEDS}" "${PATH_KIND}" <<'PY'
import json, os, re, sys
out, poses, kinds, seeds, path = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4].split(), sys.argv[5]
def ratio(a, b):
    return a / b if b else 1.0
print(f"poses {poses}, path {path}; session 2 revisits an unchanged room; growth of map.db over session 2")
print(f"{'scene':<12}{'session 1':>11}{'growth':>9}{'revisits':>10}{'in part':>8}{'mapped':>8}"
      f"{'changes':>9}{'inv P/R':>11}   |{'growth off':>11}{'mapped':>8}{'changes':>9}{'inv P/R':>11}")
totals = {t: {"first": 0, "growth": 0, "changes": 0, "tp": 0, "fp": 0, "dup": 0, "real": 0}
          for t in ("true", "false")}
revisits_total = mapped_total = part_total = 0
for kind in kinds:
    for seed in seeds:
        line = f"{kind + '-' + seed:<12}"
        for thinning in ("true", "false"):
            base = os.path.join(out, f"{kind}-{seed}-{path}-{poses}-thinning-{thinning}")
            with open(base + ".bytes") as f:
                first, both = (int(x) for x in f.read().split())
            with open(base + ".eval.json") as f:
                e = json.load(f)
            with open(base + ".log") as f:
                log = f.read()
            mapped = re.findall(r"session 2: (\d+) keyframes mapped", log)
            revisits = re.findall(r"(\d+) kept as revisits", log)
            part = re.findall(r"\((\d+) of them with only the part new", log)
            part = int(part[-1]) if part else 0
            mapped = int(mapped[-1]) if mapped else 0
            revisits = int(revisits[-1]) if revisits else 0
            reported = e["changes"]["all"]["reported"]
            a = e["all"]
            t = totals[thinning]
            t["first"] += first
            t["growth"] += both - first
            t["changes"] += reported
            t["tp"] += a["tp"]; t["fp"] += a["fp"]; t["dup"] += a["duplicates"]; t["real"] += a["real"]
            inv = f"{ratio(a['tp'], a['tp'] + a['fp'] + a['duplicates']):.2f}/{ratio(a['tp'], a['real']):.2f}"
            growth = f"{100.0 * (both - first) / first:.1f}%"
            if thinning == "true":
                revisits_total += revisits
                mapped_total += mapped
                part_total += part
                line += f"{first / 1e6:>9.1f}MB{growth:>9}{revisits:>10}{part:>8}{mapped:>8}{reported:>9}{inv:>11}   |"
            else:
                line += f"{growth:>11}{mapped:>8}{reported:>9}{inv:>11}"
        print(line)
print()
for thinning, name in (("true", "thinning on "), ("false", "thinning off")):
    t = totals[thinning]
    print(f"{name}: growth {100.0 * t['growth'] / t['first']:.1f}% of session 1 "
          f"({t['growth'] / 1e6:.1f} MB over {t['first'] / 1e6:.1f} MB); changes reported "
          f"{t['changes']} (all false); inventory P {ratio(t['tp'], t['tp'] + t['fp'] + t['dup']):.3f} "
          f"R {ratio(t['tp'], t['real']):.3f}")
print(f"session 2 keyframes with thinning: {revisits_total} kept as revisits, {mapped_total} mapped "
      f"({part_total} of them with only their new part)")
PY
