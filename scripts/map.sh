#!/usr/bin/env bash
# objmap's main job: set up (scripts/setup.sh), map an RGB-D sequence and print its inventory.
#   bash scripts/map.sh                                  a synthetic office, scored
#   bash scripts/map.sh DATASET [OUT_DIR] [extra `objmap map` options]
# Without DATASET it generates the office scene (seed 1, 300 frames, tests/sim) with its ground
# truth, maps it with the ground-truth detector's detections and prints the inventory next to
# the ground truth (`objmap eval`). OUT_DIR defaults to out/<dataset name>.
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"

if (($# == 0)); then
  bash "${ROOT}/scripts/setup.sh"
  readonly SCENE="${ROOT}/out/sim-office"
  "${BUILD_DIR}/tests/sim/objmap_sim" --out "${SCENE}" --kind office --seed 1 --frames 300
  "${BUILD_DIR}/client/cli/objmap" map "${SCENE}" --detections "${SCENE}/detections.json" \
    --out "${SCENE}-map"
  echo
  echo "the map against the scene's ground truth (docs/evaluation.md says how it is scored):"
  "${BUILD_DIR}/client/cli/objmap" eval "${SCENE}-map" --gt "${SCENE}/ground_truth.json"
  exit 0
fi

readonly DATASET="$1"
readonly OUT_DIR="${2:-${ROOT}/out/$(basename "${DATASET}")}"
shift $(($# > 2 ? 2 : $#))
if [[ ! -d "${DATASET}" ]]; then
  echo "map: dataset ${DATASET} not found. Pass a 7-Scenes or TUM RGB-D folder:" >&2
  echo "  bash scripts/map.sh /path/to/sequence [out_dir]" >&2
  exit 1
fi
bash "${ROOT}/scripts/setup.sh"
"${BUILD_DIR}/client/cli/objmap" map "${DATASET}" --out "${OUT_DIR}" "$@"
