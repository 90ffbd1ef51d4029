#!/usr/bin/env bash
# Change detection on synthetic revisits: each scene is rendered twice (objmap_sim --revisit: some
# objects removed, some moved, some added, the camera starting elsewhere), both sessions are
# mapped into one map folder (objmap map --map), and the changes the map reports in session 2 are
# scored against the revisit's changes.json (objmap eval --changes). The second session is also
# mapped alone: its objects scored against the same ground truth are the single-session figures
# the two-session map's present objects are compared with (docs/evaluation.md).
#   bash scripts/eval_changes.sh [OUT_DIR]
# Environment (defaults in brackets):
#   OBJMAP_EVAL_KINDS   [desk office kitchen lab]
#   OBJMAP_EVAL_SEEDS   [41 42]    (the project's tests use seeds 1 to 4)
#   OBJMAP_EVAL_FRAMES  [300]      frames per session
#   OBJMAP_EVAL_POSES   [input]    input: the sequences' poses; estimate: objmap's own tracking
#                                  (session 2 is placed by relocalisation into session 1's map)
#   OBJMAP_EVAL_MAP_FLAGS []       extra objmap map flags (--set KEY=V ...)
#   OBJMAP_JOBS         [number of cores]   scenes at once
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"
readonly OUT="${1:-${ROOT}/out/eval-changes}"
readonly KINDS="${OBJMAP_EVAL_KINDS:-desk office kitchen lab}"
readonly SEEDS="${OBJMAP_EVAL_SEEDS:-41 42}"
readonly FRAMES="${OBJMAP_EVAL_FRAMES:-300}"
readonly POSES="${OBJMAP_EVAL_POSES:-input}"
readonly JOBS="${OBJMAP_JOBS:-$(nproc)}"
readonly SIM="${BUILD_DIR}/tests/sim/objmap_sim"
readonly CLI="${BUILD_DIR}/client/cli/objmap"

for tool in "${SIM}" "${CLI}"; do
  if [[ ! -x "${tool}" ]]; then
    echo "eval_changes: ${tool} is missing: build first (bash scripts/setup.sh)" >&2
    exit 1
  fi
done
case "${POSES}" in input | estimate) ;; *)
  echo "eval_changes: OBJMAP_EVAL_POSES must be input or estimate, not ${POSES}" >&2
  exit 2
  ;;
esac
mkdir -p "${OUT}"

run_scene() {
  local kind="$1" seed="$2"
  local first="${OUT}/${kind}-${seed}-a" second="${OUT}/${kind}-${seed}-b"
  if [[ ! -f "${second}/changes.json" ]]; then
    "${SIM}" --out "${first}" --kind "${kind}" --seed "${seed}" --frames "${FRAMES}" \
      --revisit "${second}" >"${OUT}/${kind}-${seed}.sim.log" 2>&1
  fi
  local map="${OUT}/${kind}-${seed}-${POSES}-map" alone="${OUT}/${kind}-${seed}-${POSES}-alone"
  rm -rf "${map}" "${alone}"
  local session
  for session in "${first}" "${second}"; do
    # shellcheck disable=SC2086
    "${CLI}" map "${session}" --detections "${session}/detections.json" --poses "${POSES}" \
      --map "${map}" ${OBJMAP_EVAL_MAP_FLAGS:-} >>"${map}.log" 2>&1
  done
  # shellcheck disable=SC2086
  "${CLI}" map "${second}" --detections "${second}/detections.json" --poses "${POSES}" \
    --out "${alone}" ${OBJMAP_EVAL_MAP_FLAGS:-} >"${alone}.log" 2>&1
  "${CLI}" eval "${map}" --changes "${second}/changes.json" --gt "${second}/ground_truth.json" \
    --gt-before "${first}/ground_truth.json" --since-session 2 --json >"${map}.eval.json" \
    2>/dev/null
  # The same, with look-alike objects' changes scored as the ground truth writes them.
  "${CLI}" eval "${map}" --changes "${second}/changes.json" --gt "${second}/ground_truth.json" \
    --gt-before "${first}/ground_truth.json" --since-session 2 --lookalikes-as-written --json \
    >"${map}.strict.eval.json" 2>/dev/null
  "${CLI}" eval "${alone}" --gt "${second}/ground_truth.json" --json >"${alone}.eval.json" \
    2>/dev/null
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
  echo "eval_changes: a scene failed; its logs are in ${OUT}" >&2
  exit 1
fi

/usr/bin/python3 - "${OUT}" "${POSES}" "${KINDS}" "${SEEDS}" <<'PY'
import json, os, re, sys
out, poses, kinds, seeds = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4].split()
kinds_of_change = ["removed", "moved", "added", "all"]
pooled = {k: {"real": 0, "reported": 0, "tp": 0, "fp": 0, "fn": 0} for k in kinds_of_change}
kept = total_moves = reread = 0
strict = {"tp": 0, "fp": 0, "real": 0}
objects = {"map": {"tp": 0, "fp": 0, "fn": 0, "real": 0, "dup": 0},
           "alone": {"tp": 0, "fp": 0, "fn": 0, "real": 0, "dup": 0}}
def ratio(a, b):
    return a / b if b else 1.0
print(f"poses {poses}; change detection in session 2, one line per scene")
print(f"{'scene':<12}" + "".join(f"{k + ' P/R':>14}" for k in kinds_of_change) +
      f"{'kept id':>9}{'placed':>12}{'inv P/R (2 sessions)':>22}{'inv P/R (alone)':>18}")
for kind in kinds:
    for seed in seeds:
        base = os.path.join(out, f"{kind}-{seed}-{poses}")
        with open(base + "-map.eval.json") as f:
            e = json.load(f)
        with open(base + "-alone.eval.json") as f:
            alone = json.load(f)
        changes = e["changes"]
        line = f"{kind + '-' + seed:<12}"
        for k in kinds_of_change:
            c = changes[k]
            for key in pooled[k]:
                pooled[k][key] += c[key]
            line += f"{c['precision']:>7.2f}/{c['recall']:<6.2f}"
        kept += changes["moved_kept_id"]
        total_moves += changes["moved_total"]
        reread += changes["lookalike_groups_reread"]
        with open(base + "-map.strict.eval.json") as f:
            strict_all = json.load(f)["changes"]["all"]
        for key in strict:
            strict[key] += strict_all[key]
        # Keyframes of session 2 that were mapped, from the map run's log.
        placed = "-"
        with open(base + "-map.log") as f:
            found = re.findall(r"session 2: (\d+) keyframes mapped", f.read())
        if found:
            placed = found[-1]
        inv = []
        for name, report in (("map", e), ("alone", alone)):
            a = report["all"]
            objects[name]["tp"] += a["tp"]
            objects[name]["fp"] += a["fp"]
            objects[name]["fn"] += a["fn"]
            objects[name]["dup"] += a["duplicates"]
            objects[name]["real"] += a["real"]
            inv.append(f"{ratio(a['tp'], a['tp'] + a['fp'] + a['duplicates']):.2f}/"
                       f"{ratio(a['tp'], a['real']):.2f}")
        line += f"{changes['moved_kept_id']:>5}/{changes['moved_total']:<3}{placed:>12}"
        line += f"{inv[0]:>22}{inv[1]:>18}"
        print(line)
print()
print("pooled")
for k in kinds_of_change:
    p = pooled[k]
    print(f"  {k:<8} real {p['real']:>3}  reported {p['reported']:>3}  tp {p['tp']:>3}  "
          f"fp {p['fp']:>3}  fn {p['fn']:>3}  precision {ratio(p['tp'], p['tp'] + p['fp']):.3f}"
          f"  recall {ratio(p['tp'], p['real']):.3f}")
print(f"  moved objects that kept their id: {kept} of {total_moves}")
print(f"  groups of look-alikes read as the reports pair them: {reread}; as the ground truth "
      f"writes them: precision {ratio(strict['tp'], strict['tp'] + strict['fp']):.3f} "
      f"recall {ratio(strict['tp'], strict['real']):.3f}")
for name in ("map", "alone"):
    o = objects[name]
    label = "two-session map" if name == "map" else "session 2 alone"
    print(f"  objects present in session 2, {label}: precision "
          f"{ratio(o['tp'], o['tp'] + o['fp'] + o['dup']):.3f} recall {ratio(o['tp'], o['real']):.3f}")
PY
