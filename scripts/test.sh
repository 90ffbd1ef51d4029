#!/usr/bin/env bash
# Sets up (scripts/setup.sh), installs what the browser test needs (Chromium, puppeteer-core) and
# runs the whole test suite with ctest. Tests that need
# ../shared/data or the detector model skip with a message naming what is absent. Then, where
# clang with libFuzzer is installed, a short run of every fuzz target (scripts/fuzz.sh,
# OBJMAP_FUZZ_SECONDS each, default 30; 0 skips it).
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"

bash "${ROOT}/scripts/setup.sh"

# The viewer's browser test drives Debian's Chromium headless with puppeteer-core (npm); both are
# for the tests only. Without them that test skips and says why.
install_browser_test_tools() {
  if ! command -v chromium >/dev/null 2>&1; then
    local sudo=""
    if [[ "$(id -u)" -ne 0 ]]; then sudo="sudo"; fi
    echo "test: installing chromium (the viewer's browser test)"
    ${sudo} apt-get update -qq
    DEBIAN_FRONTEND=noninteractive ${sudo} apt-get install -y -qq --no-install-recommends \
      chromium >/dev/null
  fi
  local driver="${ROOT}/tests/http_viewer/browser"
  if [[ ! -f "${driver}/node_modules/.package-lock.json" ||
        "${driver}/package-lock.json" -nt "${driver}/node_modules/.package-lock.json" ]]; then
    (cd "${driver}" && npm ci --no-audit --no-fund --loglevel=error)
  fi
}
install_browser_test_tools || echo "test: the browser test's tools are missing; it will skip" >&2

ctest --test-dir "${BUILD_DIR}" --output-on-failure -j "${OBJMAP_JOBS:-$(nproc)}"
if [[ "${OBJMAP_FUZZ_SECONDS:-30}" != 0 ]]; then
  bash "${ROOT}/scripts/fuzz.sh" "${OBJMAP_FUZZ_SECONDS:-30}"
fi
