#!/usr/bin/env bash
# A map made in two sessions against the same map made in one, through objmap_server with
# estimated poses (docs/evaluation.md, "Sessions and relocalisation"):
#   bash scripts/eval_sessions.sh [DATASET] [FIRST_END] [SECOND_START] [FRAMES]
# Defaults: ../shared/data/redkitchen, frames 0..449 as session 1, then a server restart, then
# 550..999 as session 2 (the camera starts where session 1 never was at its end). The single
# session maps 0..999. Printed: keyframes sent and mapped per session, whether session 2's first
# keyframe was placed (the sessions table, with the keyframes kept as revisits of unchanged
# views), the database's size after each session, the ATE of session 2's keyframes
# in both maps (TUM alignment over those keyframes, against the dataset's poses), and both
# inventories. OBJMAP_SERVER_FLAGS: more objmap_server flags (--set thinning.enabled=false ...).
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"
readonly DATASET="${1:-${ROOT}/../shared/data/redkitchen}"
readonly FIRST_END="${2:-449}"
readonly SECOND_START="${3:-550}"
readonly FRAMES="${4:-1000}"
readonly OBJMAP="${BUILD_DIR}/client/cli/objmap"
readonly SERVER="${BUILD_DIR}/server/apps/objmap_server"
readonly WORK="$(mktemp -d /tmp/objmap_sessions.XXXXXX)"
trap 'kill ${SERVER_PID:-0} 2>/dev/null || true' EXIT

SERVER_PID=""
# Starts objmap_server with estimated poses on database $1; sets ADDRESS.
start_server() {
  local log="${WORK}/server.$(basename "$1").$(date +%s%N).log"
  # shellcheck disable=SC2086
  "${SERVER}" --db "$1" --listen 127.0.0.1:0 --set server.pose_source=estimate \
    ${OBJMAP_SERVER_FLAGS:-} >"${log}" 2>&1 &
  SERVER_PID=$!
  for _ in $(seq 1 600); do
    ADDRESS="$(sed -n 's/.*listening on \([0-9.:]*\).*/\1/p' "${log}" | head -1)"
    [[ -n "${ADDRESS}" ]] && return 0
    sleep 0.5
  done
  echo "objmap_server did not start; its log:" >&2
  cat "${log}" >&2
  exit 1
}
stop_server() {
  kill -TERM "${SERVER_PID}"
  wait "${SERVER_PID}" || true
  SERVER_PID=""
}

# The keyframes of the map as TUM lines (stamp = frame index / 30, named frame-NNNNNN) from
# `objmap keyframes`, only frames >= $2; and the dataset's poses of the same frames.
keyframes_as_tum() {
  /usr/bin/python3 - "$1" "$2" "${DATASET}" "$3" "$4" <<'PY'
import math, sys
keyframes, first, dataset, estimated_out, reference_out = sys.argv[1:6]
first = int(first)

def quaternion(R):  # rotation matrix -> (x, y, z, w)
    trace = R[0][0] + R[1][1] + R[2][2]
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        return ((R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s, s / 4)
    i = max(range(3), key=lambda k: R[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + R[i][i] - R[j][j] - R[k][k])
    q = [0.0] * 3
    q[i], q[j], q[k] = s / 4, (R[j][i] + R[i][j]) / s, (R[k][i] + R[i][k]) / s
    return (q[0], q[1], q[2], (R[k][j] - R[j][k]) / s)

est, ref = open(estimated_out, "w"), open(reference_out, "w")
for line in open(keyframes):
    if line.startswith("#") or not line.strip():
        continue
    values, comment = line.split("#", 1)
    name = comment.split()[0]
    index = int(name.split("-")[1])
    if index < first:
        continue
    stamp = index / 30.0
    est.write("%.6f %s\n" % (stamp, " ".join(values.split()[1:8])))
    T = [[float(v) for v in row.split()] for row in open("%s/%s.pose.txt" % (dataset, name))
         if row.strip()]
    ref.write("%.6f %f %f %f %f %f %f %f\n" % (stamp, T[0][3], T[1][3], T[2][3], *quaternion(T)))
PY
}

echo "== two sessions: frames 0..${FIRST_END}, restart, ${SECOND_START}..$((FRAMES - 1))"
start_server "${WORK}/two.db"
"${OBJMAP}" ingest "${DATASET}" --server "${ADDRESS}" --max-frames "$((FIRST_END + 1))" \
  | tail -2
stop_server
echo "database after session 1: $(stat -c %s "${WORK}/two.db") bytes"
start_server "${WORK}/two.db"
start_s=$(date +%s.%N)
"${OBJMAP}" ingest "${DATASET}" --server "${ADDRESS}" --first-frame "${SECOND_START}" \
  --max-frames "$((FRAMES - SECOND_START))" --session "second" | tail -2
echo "session 2 ingest took $(echo "$(date +%s.%N) - ${start_s}" | bc) s"
"${OBJMAP}" sessions --server "${ADDRESS}"
"${OBJMAP}" keyframes --server "${ADDRESS}" --out "${WORK}/two.keyframes"
"${OBJMAP}" inventory --server "${ADDRESS}" > "${WORK}/two.inventory"
stop_server
echo "database after session 2: $(stat -c %s "${WORK}/two.db") bytes"

echo "== one session: frames 0..$((FRAMES - 1))"
start_server "${WORK}/one.db"
"${OBJMAP}" ingest "${DATASET}" --server "${ADDRESS}" --max-frames "${FRAMES}" | tail -2
"${OBJMAP}" keyframes --server "${ADDRESS}" --out "${WORK}/one.keyframes"
"${OBJMAP}" inventory --server "${ADDRESS}" > "${WORK}/one.inventory"
stop_server

for run in two one; do
  keyframes_as_tum "${WORK}/${run}.keyframes" "${SECOND_START}" "${WORK}/${run}.est.txt" \
    "${WORK}/${run}.ref.txt"
  echo "== ${run} session(s): frames ${SECOND_START}.. in the map: $(wc -l < "${WORK}/${run}.est.txt") keyframes"
  "${OBJMAP}" eval-trajectory "${WORK}/${run}.est.txt" "${WORK}/${run}.ref.txt"
done
echo "== inventories (two sessions | one session)"
paste "${WORK}/two.inventory" "${WORK}/one.inventory"
echo "work files in ${WORK}"
