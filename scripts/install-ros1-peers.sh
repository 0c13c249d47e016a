#!/usr/bin/env bash
# Install the real ROS 1 (ros_comm 1.15, Noetic era) from Debian, as interop peers for the
# tests and benchmarks, and the web peers of the bridge tests (Node, chromium, and the npm
# packages pinned in tests/peers/web). rostools itself never needs these. Idempotent and quiet
# when done.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  ros-core
  python3-rospy python3-rostopic python3-rosservice python3-rosparam python3-rosnode
  python3-rosmsg python3-rosbag python3-rosmaster python3-genpy python3-genmsg
  libroscpp-dev librosbag-dev
  ros-std-msgs ros-geometry-msgs ros-sensor-msgs ros-std-srvs
  python3-std-msgs python3-geometry-msgs python3-sensor-msgs python3-std-srvs
  # more message packages, so the type-system interop covers hundreds of types
  ros-nav-msgs ros-diagnostic-msgs ros-actionlib-msgs ros-shape-msgs ros-stereo-msgs
  ros-trajectory-msgs ros-visualization-msgs ros-tf2-msgs ros-rosgraph-msgs ros-map-msgs
  ros-roscpp-msg ros-topic-tools-srvs
  python3-nav-msgs python3-diagnostic-msgs python3-actionlib-msgs python3-shape-msgs
  python3-stereo-msgs python3-trajectory-msgs python3-visualization-msgs python3-tf2-msgs
  python3-rosgraph-msgs python3-map-msgs python3-roscpp-msg
  libstd-msgs-dev libgeometry-msgs-dev libsensor-msgs-dev libstd-srvs-dev
  libnav-msgs-dev libdiagnostic-msgs-dev libactionlib-msgs-dev libshape-msgs-dev
  libstereo-msgs-dev libtrajectory-msgs-dev libvisualization-msgs-dev libtf2-msgs-dev
  libmap-msgs-dev libroscpp-msg-dev libros-rosgraph-msgs-dev
  # actionlib: a real SimpleActionServer and SimpleActionClient for `rostools action`
  python3-actionlib
  # Graphviz's dot renders `node graph -o graph.svg|png`
  graphviz
  # the docs' examples pipe JSON into jq (tests/integration/test_doc_examples.py)
  jq
  g++ make
  # the shells the completion tests drive, and rosbash (rostopic's own completion) to compare
  zsh fish rosbash
  # the bridge tests drive Foxglove Studio in a headless browser (tests/peers/web)
  chromium
  # the real rosbridge_server 0.11.17 (tests/peers/rosbridge), a parity peer of the bridge;
  # tornado too, since rosbridge_server's __init__ imports its tornado handler
  python3-twisted python3-autobahn python3-tornado python3-bson python3-pil python3-distutils
  # tf2 and tf's tools, peers of `rostools tf` (echo.py, view_frames, tf_echo, tf_monitor,
  # static_transform_publisher, tf2_py's BufferCore)
  tf2-tools python3-tf2-ros libtf2-ros-dev tf-tools
)
# Node and npm, unless some are on PATH already: NodeSource's nodejs bundles npm and conflicts
# with Debian's npm package, which would replace it with Debian's older Node.
command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
      echo "install-ros1-peers: need root to install: ${missing[*]}" >&2; exit 1
    fi
  else
    SUDO=
  fi
  echo "install-ros1-peers: installing ${#missing[@]} Debian packages" >&2
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq >/dev/null
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The web peers' npm packages, exactly as the lock file pins them (npm ci, never npm install),
# when node_modules is missing or older than the lock file. npm ci writes
# node_modules/.package-lock.json last, so its presence also says the last install finished.
web="$(cd "$(dirname "$0")/.." && pwd)/tests/peers/web"
if [ ! "$web/node_modules/.package-lock.json" -nt "$web/package-lock.json" ]; then
  echo "install-ros1-peers: npm ci in $web" >&2
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
