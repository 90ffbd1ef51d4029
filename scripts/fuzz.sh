#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) in an instrumented build of their own and runs each
# for SECONDS (default 60). Prints the executions of each; a crash, a sanitizer report or a
# leak is a finding: its input goes to build-fuzz/findings/<target>/ and the script fails.
# Needs clang with libFuzzer (Debian: clang); without it, says so and exits 0.
#   scripts/fuzz.sh [SECONDS]
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD="${OBJMAP_FUZZ_BUILD_DIR:-${ROOT}/build-fuzz}"
readonly SECONDS_EACH="${1:-60}"
readonly TARGETS=(fuzz_keyframe_request fuzz_image_decoding fuzz_keyframe_codec fuzz_pcd_reader
                  fuzz_dataset_readers)

if ! command -v clang++ >/dev/null 2>&1; then
  echo "fuzz: SKIPPED: needs clang++ with libFuzzer (apt-get install clang)"
  exit 0
fi
probe="$(mktemp -d)"
printf 'extern "C" int LLVMFuzzerTestOneInput(const char*, unsigned long) { return 0; }\n' \
  > "${probe}/probe.cc"
if ! clang++ -fsanitize=fuzzer "${probe}/probe.cc" -o "${probe}/probe" 2>/dev/null; then
  echo "fuzz: SKIPPED: clang++ cannot link -fsanitize=fuzzer (libFuzzer runtime missing)"
  rm -rf "${probe}"
  exit 0
fi
rm -rf "${probe}"

CC=clang CXX=clang++ cmake -S "${ROOT}" -B "${BUILD}" -G Ninja -DOBJMAP_FUZZ=ON \
  -DBUILD_TESTING=OFF -DOBJMAP_WITH_ROS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "${BUILD}" --target "${TARGETS[@]}" -- -j "${OBJMAP_JOBS:-$(nproc)}"

status=0
printf '%-24s %12s %10s  %s\n' target executions "exec/s" result
for target in "${TARGETS[@]}"; do
  name="${target#fuzz_}"
  corpus="${BUILD}/corpus/${name}"
  findings="${BUILD}/findings/${name}"
  mkdir -p "${corpus}" "${findings}"
  log="${BUILD}/${target}.log"
  # The first corpus folder collects what the run finds; the seeds stay as they are.
  if "${BUILD}/tests/fuzz/${target}" -max_total_time="${SECONDS_EACH}" -print_final_stats=1 \
      -max_len=8192 -rss_limit_mb=4096 -timeout=20 -seed="${OBJMAP_FUZZ_SEED:-1}" \
      -artifact_prefix="${findings}/" \
      "${corpus}" "${ROOT}/tests/fuzz/corpus/${name}" >"${log}" 2>&1; then
    result="no finding"
  else
    result="FINDING (see ${log}, input in ${findings}/)"
    status=1
  fi
  executions="$(sed -n 's/^stat::number_of_executed_units: *//p' "${log}" | tail -1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "${log}" | tail -1)"
  printf '%-24s %12s %10s  %s\n' "${target}" "${executions:-?}" "${rate:-?}" "${result}"
done
exit "${status}"
