#!/usr/bin/env bash
# The real rosbridge_suite 0.11.17 (the last ROS 1 release: rosbridge_server's websocket node,
# rosbridge_library, rosapi), made runnable on Debian's ROS 1 (ros_comm 1.15) and system python,
# with no catkin: a parity peer of `rostools bridge`'s rosbridge protocol.
#
#   setup.sh setup DIR   extract the packages into DIR/src and generate their message and
#                        service classes with genpy (idempotent for one DIR); DIR is scratch
#   setup.sh env DIR     print the PYTHONPATH and ROS_PACKAGE_PATH exports for running them
#
# tests/support/rosbridge.py calls it, then starts rosapi_node and rosbridge_websocket itself
# (by PID, on a free port, against a test's master). The apt packages it needs (python3-twisted,
# -autobahn, -tornado, -bson, -pil) come from scripts/install-ros1-peers.sh.
#
# Environment:
#   RBS_TARBALL  the release tarball (default: ../shared/peers/rosbridge_suite-0.11.17.tar.gz
#                beside the clone, where the corpus is)
#   PY           the python with Debian's rospy (default /usr/bin/python3)
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
TARBALL=${RBS_TARBALL:-$ROOT/../shared/peers/rosbridge_suite-0.11.17.tar.gz}
PY=${PY:-/usr/bin/python3}
GENPY_DIR=${GENPY_DIR:-/usr/lib/genpy}   # Debian's python3-genpy: genmsg_py.py, gensrv_py.py
ROS_SHARE=${ROS_SHARE:-/usr/share}       # Debian's .msg files: /usr/share/<pkg>/msg
PKGS="rosapi rosbridge_library rosbridge_msgs rosbridge_server"

die() { echo "rosbridge setup.sh: $*" >&2; exit 1; }

env_exports() {
  local src=$1/src pp="" p
  for p in $PKGS rosauth; do pp="$pp${pp:+:}$src/$p/src"; done
  echo "export PYTHONPATH=$pp${PYTHONPATH:+:$PYTHONPATH}"
  # ros_loader calls roslib.launcher.load_manifest(pkg) before importing pkg.msg/srv: rospack
  # must find the extracted packages, and Debian's under /usr/share.
  echo "export ROS_PACKAGE_PATH=$src:$ROS_SHARE"
}

extract() {
  local src=$1 p
  [ -f "$TARBALL" ] || die "no rosbridge_suite tarball at $TARBALL (set RBS_TARBALL)"
  rm -rf "$src"; mkdir -p "$src"
  tar -xzf "$TARBALL" -C "$src" --strip-components=1 \
    $(for p in $PKGS; do echo "rosbridge_suite-0.11.17/$p"; done)
  # The one source edit: 0.11.17 puts --address only into the ws:// URI and listens on every
  # interface (listenWS's interface defaults to ''). Pass it through, to bind loopback.
  local ws=$src/rosbridge_server/scripts/rosbridge_websocket
  sed -i 's/listenWS(factory, context_factory)$/listenWS(factory, context_factory, interface=address)/' "$ws"
  grep -q 'interface=address' "$ws" || die "could not patch listenWS in $ws"
  # rosauth (GT-RAIL/rosauth, BSD): rosbridge_server imports rosauth.srv.Authentication even
  # with authentication off. Only its one service file is needed, reproduced here.
  mkdir -p "$src/rosauth/srv"
  cat > "$src/rosauth/package.xml" <<'XML'
<?xml version="1.0"?>
<package format="2"><name>rosauth</name><version>1.0.1</version><description>Authentication.srv only</description>
<maintainer email="none@example.com">none</maintainer><license>BSD</license><buildtool_depend>catkin</buildtool_depend></package>
XML
  cat > "$src/rosauth/srv/Authentication.srv" <<'SRV'
# MAC string given by the client
string mac
# IP of the client
string client
# IP of the destination
string dest
# Random string given by the client
string rand
# Time of the authorization request given by the client
time t
# User level as a string given by the client
string level
# End time of the client's session given by the client
time end
---
# If the user has proper authentication
bool authenticated
SRV
}

generate() {
  # genpy into <pkg>/src/<pkg>/{msg,srv}, next to the package's own python, as catkin's devel
  # space would merge them; included: the package and the Debian messages they reference.
  local src=$1 p inc d
  for p in rosapi rosbridge_library rosbridge_msgs rosauth; do
    d=$src/$p/src/$p; mkdir -p "$d"; [ -f "$d/__init__.py" ] || : > "$d/__init__.py"
    inc="-I $p:$src/$p/msg -I std_msgs:$ROS_SHARE/std_msgs/msg -I geometry_msgs:$ROS_SHARE/geometry_msgs/msg"
    if compgen -G "$src/$p/msg/*.msg" >/dev/null; then
      "$PY" "$GENPY_DIR/genmsg_py.py" -p "$p" -o "$d/msg" $inc "$src/$p"/msg/*.msg
      "$PY" "$GENPY_DIR/genmsg_py.py" --initpy -o "$d/msg"
    fi
    if compgen -G "$src/$p/srv/*.srv" >/dev/null; then
      "$PY" "$GENPY_DIR/gensrv_py.py" -p "$p" -o "$d/srv" $inc "$src/$p"/srv/*.srv
      "$PY" "$GENPY_DIR/gensrv_py.py" --initpy -o "$d/srv"
    fi
  done
}

setup() {
  local dir=$1 stamp
  mkdir -p "$dir"
  stamp="0.11.17 $(sha1sum "$0" | cut -c1-12)"
  if [ "$(cat "$dir/src/.stamp" 2>/dev/null)" != "$stamp" ]; then
    extract "$dir/src" >/dev/null; generate "$dir/src" >/dev/null
    echo "$stamp" > "$dir/src/.stamp"
  fi
  eval "$(env_exports "$dir")"
  "$PY" -W ignore -c 'import rosapi.srv, rosapi.msg, rosbridge_msgs.msg, rosauth.srv, rosbridge_library.rosbridge_protocol, autobahn, twisted, tornado, bson, PIL' \
    >/dev/null || die "rosbridge's imports failed after setup (scripts/install-ros1-peers.sh installs its apt packages)"
}

case "${1:-}" in
  setup) [ -n "${2:-}" ] || die "usage: $0 setup DIR"; setup "$2" ;;
  env) [ -n "${2:-}" ] || die "usage: $0 env DIR"; env_exports "$2" ;;
  *) sed -n '2,19p' "$0"; exit 2 ;;
esac
