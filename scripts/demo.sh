#!/usr/bin/env bash
# The main job of hidden_rooms, as far as the package goes today: sets up, then renders the default world
# with its closable doors closed (the rooms a robot could not see) into demo_output/.
#   scripts/demo.sh [--world WORLD.xml] [--gui]
# --gui also shows the rendered world in rviz (needs a display).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ROS 1 on Debian runs on Debian's Python: keep /usr/bin ahead of any other python3 on PATH.
export PATH="/usr/bin:$PATH"
WORLD="$ROOT/worlds/medium_1.xml"
GUI=false
while [ $# -gt 0 ]; do
  case "$1" in
    --world) WORLD="$(realpath "$2")"; shift 2 ;;
    --gui) GUI=true; shift ;;
    -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
    *) echo "demo: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

LOG="$(mktemp)"
echo "demo: setting up (log: $LOG)"
bash "$ROOT/scripts/setup.sh" > "$LOG" 2>&1 || { cat "$LOG"; exit 1; }
# shellcheck disable=SC1091
set +u && source "$ROOT/.ws/devel/setup.bash" && set -u

OUT="$ROOT/demo_output"
mkdir -p "$OUT"
echo "demo: world $WORLD"
rosrun hidden_rooms render_environment "$WORLD" --out "$OUT/ground_truth"
rosrun hidden_rooms render_environment "$WORLD" --out "$OUT/closed_doors" --closed all
cat <<MSG
demo: written
  $OUT/ground_truth/map.yaml      the complete floor (all doors open)
  $OUT/ground_truth/spaces.png    label image of its spaces
  $OUT/closed_doors/map.yaml      the floor with every closable door shut
  $OUT/closed_doors/doors.yaml    those closed doors (map frame, metres)
  $OUT/closed_doors/preview.png   picture: closed doors in red, numbered
MSG

if $GUI; then
  roslaunch hidden_rooms view_world.launch world:="$WORLD" closed_doors:=all gui:=true
fi
