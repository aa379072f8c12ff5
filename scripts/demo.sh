#!/usr/bin/env bash
# The main job of hidden_rooms, as far as the package goes today: sets up, renders the default world with some
# doors closed and the rooms behind them unseen (the map a robot would build), predicts those rooms and scores
# the prediction against the truth. Everything goes to demo_output/.
#   scripts/demo.sh [--world WORLD.xml] [--closed 2,6,9,13] [--method default] [--gui]
# --gui also shows the world in rviz (needs a display).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ROS 1 on Debian runs on Debian's Python: keep /usr/bin ahead of any other python3 on PATH.
export PATH="/usr/bin:$PATH"
WORLD="$ROOT/worlds/medium_1.xml"
CLOSED="2,6,9,13"
METHOD="default"
GUI=false
while [ $# -gt 0 ]; do
  case "$1" in
    --world) WORLD="$(realpath "$2")"; shift 2 ;;
    --closed) CLOSED="$2"; shift 2 ;;
    --method) METHOD="$2"; shift 2 ;;
    --gui) GUI=true; shift ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "demo: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

LOG="$(mktemp)"
echo "demo: setting up (log: $LOG)"
bash "$ROOT/scripts/setup.sh" > "$LOG" 2>&1 || { cat "$LOG"; exit 1; }
# shellcheck disable=SC1091
set +u && source "$ROOT/.ws/devel/setup.bash" && set -u

OUT="$ROOT/demo_output"
rm -rf "$OUT"
mkdir -p "$OUT"
echo "demo: world $WORLD, closed doors $CLOSED, method $METHOD"
rosrun hidden_rooms render_environment "$WORLD" --out "$OUT/ground_truth"
rosrun hidden_rooms render_environment "$WORLD" --out "$OUT/explored" --closed "$CLOSED" --hide-closed-rooms
rosrun hidden_rooms predict_rooms_offline --map "$OUT/explored/map.yaml" --doors "$OUT/explored/doors.yaml" \
  --method "$METHOD" --out "$OUT/prediction" --gt-rooms "$OUT/explored/true_rooms.png"
cat <<MSG
demo: written
  $OUT/ground_truth/map.yaml       the complete floor, all doors open
  $OUT/explored/map.yaml           what the robot maps with the doors closed (the hidden rooms unknown)
  $OUT/explored/doors.yaml         the closed doors (map frame, metres)
  $OUT/explored/preview.png        picture of the world: closed doors in red, numbered
  $OUT/prediction/map.yaml         the explored map completed with the predicted rooms
  $OUT/prediction/overlay.png      picture: predicted rooms tinted, true rooms outlined in green
  $OUT/prediction/metrics.yaml     IoU per room, mean IoU, IoU_tot
MSG

if $GUI; then
  roslaunch hidden_rooms view_world.launch world:="$WORLD" closed_doors:="$CLOSED" gui:=true
fi
