#!/usr/bin/env bash
# objmap_node builds without gRPC: a tree configured with OBJMAP_WITH_GRPC=OFF has the node, its
# own sources and the configuration library compile there (where no gRPC or protobuf code is
# generated, so an include of it fails), and its link line names no gRPC, protobuf or objmap
# transport library. Linking it would rebuild the whole core a second time, which the main
# build already does.
#   no_grpc_node_build_test.sh SOURCE_DIR TREE_DIR
set -euo pipefail
readonly SOURCE_DIR="$1" TREE="$2"

fail() { echo "FAILED: $*" >&2; exit 1; }

rm -rf "${TREE}"
cmake -S "${SOURCE_DIR}" -B "${TREE}" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DOBJMAP_WITH_GRPC=OFF -DOBJMAP_WITH_ROS=ON -DBUILD_TESTING=OFF \
  -DPython3_EXECUTABLE=/usr/bin/python3 -DPYTHON_EXECUTABLE=/usr/bin/python3 >"${TREE}.configure.log" 2>&1 ||
  { cat "${TREE}.configure.log"; fail "configuring with OBJMAP_WITH_GRPC=OFF"; }

targets="$(ninja -C "${TREE}" -t targets all)"
grep -q '^objmap_node: ' <<<"${targets}" || fail "no objmap_node target with OBJMAP_WITH_GRPC=OFF"
if grep -qE '^(objmap_server|objmap_grpc_service|objmap_proto|objmap_client)[:.]' <<<"${targets}"; then
  fail "gRPC targets exist in a tree configured without gRPC"
fi

# The node's link line: every library it pulls in, transitively.
link="$(ninja -C "${TREE}" -t commands objmap_node | tail -n 1)"
grep -q -- '-o .*objmap_node' <<<"${link}" || fail "last command is not the node's link: ${link}"
if grep -qiE 'grpc|protobuf|libobjmap_proto|objmap_server_options|objmap_client' <<<"${link}"; then
  fail "objmap_node links gRPC or protobuf: ${link}"
fi
grep -q 'libobjmap_config.a' <<<"${link}" || fail "objmap_node does not link objmap_config: ${link}"

# The node's own sources and the configuration library, compiled in that tree with the commands
# ninja would run. They are run directly: through ninja each object would first wait for every
# library the node links (CMake's order-only dependencies), that is, the whole core. The
# generated ROS message headers are the one prerequisite.
ninja -C "${TREE}" objmap_msgs_generate_messages_cpp >/dev/null || fail "generating objmap_msgs"
objects=()
for source in "${SOURCE_DIR}"/server/ros_node/*.cc; do
  objects+=("server/ros_node/CMakeFiles/objmap_node.dir/$(basename "${source}").o")
done
for source in "${SOURCE_DIR}"/server/core/config/*.cc; do
  objects+=("server/core/config/CMakeFiles/objmap_config.dir/$(basename "${source}").o")
done
for object in "${objects[@]}"; do
  command="$(ninja -C "${TREE}" -t commands "${object}" | tail -n 1)"
  grep -q -- "-o ${object}" <<<"${command}" || fail "no compile command for ${object}"
  (cd "${TREE}" && mkdir -p "$(dirname "${object}")" && eval "${command}") ||
    fail "${object} does not compile without gRPC"
  [[ -s "${TREE}/${object}" ]] || fail "${object} was not written"
done
echo "objmap_node: configured, compiled and linked against no gRPC (OBJMAP_WITH_GRPC=OFF):"
printf '  %s\n' "${objects[@]}"
