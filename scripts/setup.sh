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

# Tools, not dependencies of the package: the toolchain, rosdep (which reads package.xml) and the fuzzer's runtime
# (scripts/fuzz.sh; clang itself is a test_depend).
TOOLS=(build-essential cmake git python3-rosdep2 libclang-rt-14-dev)

apt_updated=0
# Installs those of the given Debian packages that are not installed yet.
install_missing() {
  local missing=() package
  for package in "$@"; do
    [ "$(dpkg-query -W -f='${db:Status-Status}' "$package" 2>/dev/null)" = "installed" ] || missing+=("$package")
  done
  [ "${#missing[@]}" -gt 0 ] || return 0
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  if [ "$apt_updated" -eq 0 ]; then
    $sudo apt-get update -q
    apt_updated=1
  fi
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
}

install_missing "${TOOLS[@]}"

# The dependencies: every rosdep key of package.xml, resolved by rosdep without the network from Debian's list of
# ROS packages and the package's rosdep.yaml (the system keys, as rosdistro resolves them on Debian 12).
ROSDEP_HOME="$WS/rosdep"
mkdir -p "$ROSDEP_HOME/sources.list.d"
printf 'yaml file:///usr/share/python3-rosdep2/debian.yaml debian\nyaml file://%s/rosdep.yaml\n' "$ROOT" \
  >"$ROSDEP_HOME/sources.list.d/20-hidden-rooms.list"
printf '%%YAML 1.1\n---\ntype: index\nversion: 4\ndistributions: {}\n' >"$ROSDEP_HOME/index.yaml"
rosdep_offline() {
  ROSDEP_SOURCE_PATH="$ROSDEP_HOME/sources.list.d" ROS_HOME="$ROSDEP_HOME" \
    ROSDISTRO_INDEX_URL="file://$ROSDEP_HOME/index.yaml" rosdep "$@"
}
rosdep_offline update -q >/dev/null 2>&1 || rosdep_offline update  # again, to show why it failed
keys="$(/usr/bin/python3 -c '
import sys
from catkin_pkg.package import parse_package
package = parse_package(sys.argv[1])
dependencies = (package.buildtool_depends + package.build_depends + package.build_export_depends +
                package.exec_depends + package.test_depends)
print(" ".join(sorted({dependency.name for dependency in dependencies})))' "$ROOT")"
# shellcheck disable=SC2086  # one word per key
resolved="$(rosdep_offline resolve $keys)"  # "#apt" lines, then each key's packages
read -r -a PACKAGES <<<"$(grep -v '^#' <<<"$resolved" | tr '\n' ' ')"
install_missing "${PACKAGES[@]}"

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
