#!/usr/bin/env bash
# Synthetic scenes of every kind and several seeds, mapped under several keyframe policies and
# scored against their ground truth; prints one line per scene and policy, then the pooled
# figures per policy and the inventory differences between policies (docs/evaluation.md).
#   bash scripts/eval_sim.sh [OUT_DIR]
# Environment (defaults in brackets):
#   OBJMAP_EVAL_KINDS     [desk office kitchen lab]
#   OBJMAP_EVAL_SEEDS     [31 32]      seeds (the project's own scenes use 1 and 4)
#   OBJMAP_EVAL_FRAMES    [300]
#   OBJMAP_EVAL_POLICIES  [motion nth5 every]   motion: the default keyframes by camera motion;
#                         nth5: every 5th frame; every: every frame
#   OBJMAP_EVAL_DETECTOR  [gt]         gt: the scenes' ground-truth detector; centernet: the
#                         network on the rendered colour (needs the model)
#   OBJMAP_EVAL_SIM_FLAGS []           extra objmap_sim flags (--perfect, --procedural)
#   OBJMAP_EVAL_MAP_FLAGS []           extra objmap map flags (--set KEY=V ...)
#   OBJMAP_JOBS           [number of cores]   scenes mapped at once
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"
readonly OUT="${1:-${ROOT}/out/eval-sim}"
readonly KINDS="${OBJMAP_EVAL_KINDS:-desk office kitchen lab}"
readonly SEEDS="${OBJMAP_EVAL_SEEDS:-31 32}"
readonly FRAMES="${OBJMAP_EVAL_FRAMES:-300}"
readonly POLICIES="${OBJMAP_EVAL_POLICIES:-motion nth5 every}"
readonly DETECTOR="${OBJMAP_EVAL_DETECTOR:-gt}"
readonly JOBS="${OBJMAP_JOBS:-$(nproc)}"
readonly SIM="${BUILD_DIR}/tests/sim/objmap_sim"
readonly CLI="${BUILD_DIR}/client/cli/objmap"

for tool in "${SIM}" "${CLI}"; do
  if [[ ! -x "${tool}" ]]; then
    echo "eval_sim: ${tool} is missing: build first (bash scripts/setup.sh)" >&2
    exit 1
  fi
done
mkdir -p "${OUT}"

policy_flags() {
  case "$1" in
    motion) echo "" ;;
    nth5) echo "--every-nth-frame 5" ;;
    every) echo "--every-frame" ;;
    *) echo "eval_sim: unknown policy $1" >&2; return 1 ;;
  esac
}

# One scene: render it once, then map and score it under every policy.
run_scene() {
  local kind="$1" seed="$2"
  local scene="${OUT}/${kind}-${seed}"
  if [[ ! -f "${scene}/ground_truth.json" ]]; then
    # shellcheck disable=SC2086
    "${SIM}" --out "${scene}" --kind "${kind}" --seed "${seed}" --frames "${FRAMES}" \
      ${OBJMAP_EVAL_SIM_FLAGS:-} >"${scene}.sim.log" 2>&1
  fi
  local detections=""
  if [[ "${DETECTOR}" == "gt" ]]; then detections="--detections ${scene}/detections.json"; fi
  for policy in ${POLICIES}; do
    local map="${scene}-${DETECTOR}-${policy}"
    # shellcheck disable=SC2046,SC2086
    "${CLI}" map "${scene}" ${detections} $(policy_flags "${policy}") ${OBJMAP_EVAL_MAP_FLAGS:-} \
      --out "${map}" >"${map}.log" 2>&1
    "${CLI}" eval "${map}" --gt "${scene}/ground_truth.json" --json >"${map}.eval.json" \
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
  echo "eval_sim: a scene failed; its logs are in ${OUT}" >&2
  exit 1
fi

/usr/bin/python3 - "${OUT}" "${DETECTOR}" "${KINDS}" "${SEEDS}" "${POLICIES}" <<'PY'
import json, sys, os
out, detector, kinds, seeds, policies = sys.argv[1], sys.argv[2], *[a.split() for a in sys.argv[3:]]
keys = ["real", "mapped", "tp", "fp", "fn", "duplicates", "merges"]
def inventory(path):
    with open(path) as f:
        objects = json.load(f)["objects"]
    counts = {}
    for o in objects:
        if o.get("in_inventory") and o["class"] != "unknown":
            counts[o["class"]] = counts.get(o["class"], 0) + 1
    return counts
print(f"detector {detector}; one line per scene and keyframe policy")
print(f"{'scene':<14}{'policy':<8}{'keyframes':>9}" + "".join(f"{k[:5]:>7}" for k in keys) +
      f"{'prec':>7}{'recall':>7}{'acc cm':>8}")
pooled = {p: {k: 0 for k in keys} for p in policies}
accuracies = {p: [] for p in policies}
unknown = {p: {"mapped": 0, "on_real": 0, "on_missed": 0, "missed_marked": 0} for p in policies}
inventories = {}
for kind in kinds:
    for seed in seeds:
        for policy in policies:
            base = os.path.join(out, f"{kind}-{seed}-{detector}-{policy}")
            with open(base + ".eval.json") as f:
                e = json.load(f)
            with open(os.path.join(base, "objects.json")) as f:
                keyframes = json.load(f).get("keyframes", "?")
            a = e["all"]
            for k in keys:
                pooled[policy][k] += a[k]
            for k in unknown[policy]:
                unknown[policy][k] += e.get("unknown_objects", {}).get(k, 0)
            acc = e.get("mean_model_to_surface_m", -1)
            for m in e.get("matches", []):
                if m["model_to_surface_m"] >= 0:
                    accuracies[policy].append(m["model_to_surface_m"])
            inventories[(kind, seed, policy)] = inventory(os.path.join(base, "objects.json"))
            prec = a["tp"] / max(1, a["tp"] + a["fp"] + a["duplicates"])
            rec = a["tp"] / max(1, a["real"])
            print(f"{kind + '-' + seed:<14}{policy:<8}{str(keyframes):>9}" +
                  "".join(f"{a[k]:>7}" for k in keys) +
                  f"{prec:>7.3f}{rec:>7.3f}{100 * acc:>8.2f}")
print()
print("pooled over every scene")
print(f"{'policy':<8}" + "".join(f"{k[:5]:>7}" for k in keys) +
      f"{'prec':>7}{'recall':>7}{'dup+mrg':>8}{'acc cm':>8}")
for policy in policies:
    p = pooled[policy]
    prec = p["tp"] / max(1, p["tp"] + p["fp"] + p["duplicates"])
    rec = p["tp"] / max(1, p["real"])
    dm = (p["duplicates"] + p["merges"]) / max(1, p["real"])
    acc = sum(accuracies[policy]) / max(1, len(accuracies[policy]))
    print(f"{policy:<8}" + "".join(f"{p[k]:>7}" for k in keys) +
          f"{prec:>7.3f}{rec:>7.3f}{100 * dm:>7.1f}%{100 * acc:>8.2f}")
print()
print("unknown objects (segmented, never named; not in the figures above)")
for policy in policies:
    u = unknown[policy]
    print(f"{policy:<8} {u['mapped']} confirmed, {u['on_real']} on a real object, "
          f"{u['on_missed']} on one the named objects missed; "
          f"{u['missed_marked']} of the {pooled[policy]['fn']} missed objects marked by one")
if len(policies) > 1:
    print()
    print(f"inventory differences against {policies[0]} (objects added or missing, per scene)")
    for kind in kinds:
        for seed in seeds:
            ref = inventories[(kind, seed, policies[0])]
            line = []
            for policy in policies[1:]:
                inv = inventories[(kind, seed, policy)]
                diff = sum(abs(inv.get(c, 0) - ref.get(c, 0)) for c in set(ref) | set(inv))
                detail = ", ".join(f"{c} {ref.get(c, 0)}->{inv.get(c, 0)}"
                                   for c in sorted(set(ref) | set(inv))
                                   if inv.get(c, 0) != ref.get(c, 0))
                line.append(f"{policy}: {diff}" + (f" ({detail})" if detail else ""))
            print(f"  {kind}-{seed}: " + "; ".join(line))
PY
