#!/usr/bin/env bash
# Every speed benchmark in one run, each pairing objmap with its plain baseline on the same
# input, then a summary of the ratios. Figures and how to read them: docs/benchmarks.md.
#   bash scripts/bench.sh [SEQUENCE=../shared/data/redkitchen] [MOSD=../shared/data/mosd-learn]
# Set OBJMAP_BENCH_QUICK=1 for a short run (fewer keyframes; the ratios, not the record).
# Output: out/bench/<bench>.txt and the summary on stdout. Takes about 20 minutes on 2 cores.
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"
readonly SEQUENCE="${1:-${ROOT}/../shared/data/redkitchen}"
readonly MOSD="${2:-${ROOT}/../shared/data/mosd-learn}"
readonly OUT="${ROOT}/out/bench"
readonly QUICK="${OBJMAP_BENCH_QUICK:-0}"

if [[ ! -d "${SEQUENCE}" ]]; then
  echo "bench: sequence ${SEQUENCE} not found (a 7-Scenes folder such as redkitchen)" >&2
  exit 1
fi
bash "${ROOT}/scripts/setup.sh"
mkdir -p "${OUT}"
readonly BENCH="${BUILD_DIR}/tests/bench"

run() {  # run NAME COMMAND...: prints and keeps the output
  local name="$1"
  shift
  echo "== ${name}: $*"
  "$@" 2>&1 | grep -v -e '^Reading binary octree' -e '^ done\.$' | tee "${OUT}/${name}.txt"
}

if [[ "${QUICK}" == 1 ]]; then
  run occupancy "${BENCH}/occupancy_bench" "${SEQUENCE}" 4 10 2
  run regeneration "${BENCH}/regeneration_bench" "${SEQUENCE}" 100 2 2
  run association "${BENCH}/association_bench" "${SEQUENCE}" 200 1
  run stages "${BENCH}/stage_bench" "${SEQUENCE}" 4 100 1
else
  run occupancy "${BENCH}/occupancy_bench" "${SEQUENCE}" 10 10 3
  run regeneration "${BENCH}/regeneration_bench" "${SEQUENCE}" 1000 2 3
  run association "${BENCH}/association_bench" "${SEQUENCE}" 700 3
  run stages "${BENCH}/stage_bench" "${SEQUENCE}" 10 50 3
fi
if [[ -x "${BENCH}/segmentation_bench" && -d "${MOSD}" ]]; then
  run segmentation "${BENCH}/segmentation_bench" "${MOSD}" "${SEQUENCE}" 10 50 3 \
    "${ROOT}/models/centernet_coco.pb" 3
fi
if [[ -x "${BENCH}/ros_input_bench" ]]; then  # builds with ROS
  run ros_input "${BENCH}/ros_input_bench" "${SEQUENCE}" 100 20
fi

# The whole pipeline on the sequence: wall time and per-stage medians per keyframe.
echo "== pipeline: objmap map ${SEQUENCE}"
start_ns=$(date +%s%N)
"${BUILD_DIR}/client/cli/objmap" map "${SEQUENCE}" --out "${OUT}/map" >"${OUT}/pipeline.txt" 2>&1
end_ns=$(date +%s%N)
wall_s=$(awk -v ns="$((end_ns - start_ns))" 'BEGIN {printf "%.1f", ns / 1e9}')
median() {  # median COLUMN of the timings table
  tail -n +2 "${OUT}/map/timings.csv" | cut -d, -f"$1" | sort -g |
    awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'
}
ingest=$(tail -n +2 "${OUT}/map/timings.csv" | awk -F, '{print $3 + $4 + $5}' | sort -g |
  awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}')
{
  echo "wall time ${wall_s} s; median ms per keyframe: detection $(median 2)," \
    "segmentation $(median 3), association $(median 4), occupancy $(median 5)," \
    "ingest without the detector ${ingest}"
} | tee -a "${OUT}/pipeline.txt"

echo
echo "== summary (details in ${OUT})"
grep -h -e '^stock insertPointCloud' -e '^agreement' -e '^objmap projective' \
  "${OUT}/occupancy.txt" || true
grep -h -e 'full rebuild' -e 'after moving' -e 'peak resident' "${OUT}/regeneration.txt" || true
grep -h -i -e 'ratio' -e 'per pair' "${OUT}/association.txt" | head -8 || true
grep -h -i -e 'ratio' -e 'median' "${OUT}/stages.txt" | head -6 || true
if [[ -f "${OUT}/segmentation.txt" ]]; then
  grep -h -i -e 'ratio' -e 'median' -e 'segmentation' "${OUT}/segmentation.txt" | head -10 || true
fi
if [[ -f "${OUT}/ros_input.txt" ]]; then
  grep -h -e 'FrameFromMsgs' -e 'memcpy' -e 'ReadFrame' "${OUT}/ros_input.txt" || true
fi
tail -1 "${OUT}/pipeline.txt"
