#!/usr/bin/env bash
# One-command setup of hidden_rooms on Debian 12: installs the missing Debian packages, creates a catkin
# workspace in .ws/ inside the checkout (src/hidden_rooms links to the checkout) and builds it (Release, all cores).
# Idempotent: with nothing to install and nothing changed it takes seconds.
# Afterwards: source .ws/devel/setup.bash
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ROS 1 on Debian runs on Debian's Python: keep /usr/bin ahead of any other python3 on PATH.
export PATH="/usr/bin:$PATH"
WS="$ROOT/.ws"
BUILD_TYPE="${HIDDEN_ROOMS_BUILD_TYPE:-Release}"

PACKAGES=(
  build-essential cmake git
  # ROS 1 (Debian's own packages)
  catkin python3-catkin python3-catkin-pkg python3-rospkg ros-core-dev rosbash
  python3-rospy python3-roslaunch python3-rostest python3-rosbag python3-rosservice python3-rostopic
  python3-rosnode python3-rosmsg python3-roslib
  libtf2-dev libtf2-ros-dev python3-tf2-ros tf2-tools
  libnav-msgs-dev python3-nav-msgs libsensor-msgs-dev python3-sensor-msgs libgeometry-msgs-dev
  python3-geometry-msgs libvisualization-msgs-dev python3-visualization-msgs libstd-srvs-dev python3-std-srvs
  libros-rosgraph-msgs-dev python3-rosgraph-msgs
  ros-message-generation ros-message-runtime librosbag-dev librostest-dev rviz librviz-dev libtf2-msgs-dev libroslib-dev
  # algorithms and files
  libmrpt-slam-dev libmrpt-maps-dev libmrpt-nav-dev libmrpt-ros1bridge-dev libbox2d-dev liboctomap-dev
  libopencv-dev libeigen3-dev libpng-dev libtinyxml2-dev libyaml-cpp-dev libboost-program-options-dev
  # tests and scripts
  libgtest-dev googletest python3-nose python3-yaml python3-numpy python3-matplotlib python3-tqdm
  python3-opencv xvfb time
  # batch analysis: the Python module's install (setuptools) and the Dask cluster option
  python3-setuptools python3-distributed
  # fuzzing (scripts/fuzz.sh): clang with libFuzzer
  clang libclang-rt-14-dev
)

missing=()
while read -r package status; do
  [ "$status" = "installed" ] || missing+=("$package")
done < <(for p in "${PACKAGES[@]}"; do
  printf '%s %s\n' "$p" "$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || echo missing)"
done)

if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# The workspace's src/hidden_rooms mirrors the checkout with one link per top-level entry (a single link to
# the checkout would put the workspace inside itself, and rosrun's search would loop).
PKG="$WS/src/hidden_rooms"
[ -L "$PKG" ] && rm "$PKG"
mkdir -p "$PKG"
for entry in "$ROOT"/* "$ROOT"/.[!.]*; do
  [ -e "$entry" ] || continue
  case "$(basename "$entry")" in .ws|.git|demo_output) continue ;; esac
  ln -sfn "$entry" "$PKG/$(basename "$entry")"
done
find "$PKG" -maxdepth 1 -xtype l -delete  # entries removed from the checkout
cd "$WS"
catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE="$BUILD_TYPE" -j"$(nproc)" "$@"
echo "setup: built. Now run: source $WS/devel/setup.bash"
