#!/usr/bin/env bash
# objmap's main job: set up (scripts/setup.sh), map an RGB-D sequence and print its inventory.
#   bash scripts/map.sh [DATASET] [OUT_DIR] [extra `objmap map` options]
# DATASET defaults to ../shared/data/redkitchen (the 7-Scenes kitchen sequence), OUT_DIR to
# out/<dataset name>.
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly DATASET="${1:-${ROOT}/../shared/data/redkitchen}"
readonly OUT_DIR="${2:-${ROOT}/out/$(basename "${DATASET}")}"
shift $(($# > 2 ? 2 : $#))

if [[ ! -d "${DATASET}" ]]; then
  echo "map: dataset ${DATASET} not found. Pass a 7-Scenes or TUM RGB-D folder:" >&2
  echo "  bash scripts/map.sh /path/to/sequence [out_dir]" >&2
  exit 1
fi
bash "${ROOT}/scripts/setup.sh"
"${OBJMAP_BUILD_DIR:-${ROOT}/build}/client/cli/objmap" map "${DATASET}" --out "${OUT_DIR}" "$@"
