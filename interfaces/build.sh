#!/bin/sh
# Builds the ROS interface packages fastep needs that the package registry's ROS wheels lack (Nav2's nav2_msgs:
# the actions and messages fastep serves and reads; tf2_msgs' TFMessage) into a virtual environment, with the
# rosidl generators and ament_cmake of those wheels (requirements-test.txt), as the wheels install their own
# packages: libraries in VENV/lib, Python in its site-packages, definitions in VENV/share.
#   sh interfaces/build.sh .venv      (make does it when it builds .venv; not on a ROS install: colcon there)
set -e
VENV=$(cd "${1:-.venv}" && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
for pkg in tf2_msgs nav2_msgs; do
  build="$VENV/build-interfaces/$pkg"
  mkdir -p "$build"
  log="$build/build.log"
  if ! { cmake -S "$HERE/$pkg" -B "$build" -DCMAKE_INSTALL_PREFIX="$VENV" -DCMAKE_PREFIX_PATH="$VENV" \
           -DPython3_EXECUTABLE="$VENV/bin/python" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release &&
         cmake --build "$build" -j 2 && cmake --install "$build"; } > "$log" 2>&1; then
    tail -40 "$log"
    echo "interfaces/build.sh: building $pkg failed (the whole log: $log)" >&2
    exit 1
  fi
done
"$VENV/bin/python" -c 'import nav2_msgs.action, tf2_msgs.msg' || {
  echo "interfaces/build.sh: nav2_msgs or tf2_msgs built but not importable" >&2; exit 1; }
