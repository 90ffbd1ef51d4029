#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and runs the whole test suite with ctest. Tests that need
# ../shared/data or the detector model skip with a message naming what is absent.
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"

bash "${ROOT}/scripts/setup.sh"
ctest --test-dir "${BUILD_DIR}" --output-on-failure -j "${OBJMAP_JOBS:-$(nproc)}"
