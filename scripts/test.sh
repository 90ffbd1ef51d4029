#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and runs the whole test suite with ctest. Tests that need
# ../shared/data or the detector model skip with a message naming what is absent. Then, where
# clang with libFuzzer is installed, a short run of every fuzz target (scripts/fuzz.sh,
# OBJMAP_FUZZ_SECONDS each, default 30; 0 skips it).
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"

bash "${ROOT}/scripts/setup.sh"
ctest --test-dir "${BUILD_DIR}" --output-on-failure -j "${OBJMAP_JOBS:-$(nproc)}"
if [[ "${OBJMAP_FUZZ_SECONDS:-30}" != 0 ]]; then
  bash "${ROOT}/scripts/fuzz.sh" "${OBJMAP_FUZZ_SECONDS:-30}"
fi
