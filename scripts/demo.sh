#!/usr/bin/env bash
# The main job of hidden_rooms on a fresh machine: sets up, lets the simulated robot explore the default world
# with some doors closed (simulator + SLAM mapper + frontier explorer, headless, faster than real time), places
# the closed doors in its map, predicts the rooms behind them and scores the prediction against the world.
# Everything goes to demo_output/.
#   scripts/demo.sh [--world WORLD.xml] [--closed 3,5,8] [--method default] [--gui]
# --gui shows the run in rviz (needs a display).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ROS 1 on Debian runs on Debian's Python: keep /usr/bin ahead of any other python3 on PATH.
export PATH="/usr/bin:$PATH"
WORLD="$ROOT/worlds/small_1.xml"
CLOSED="3,5,8"
METHOD="default"
GUI=()
while [ $# -gt 0 ]; do
  case "$1" in
    --world) WORLD="$(realpath "$2")"; shift 2 ;;
    --closed) CLOSED="$2"; shift 2 ;;
    --method) METHOD="$2"; shift 2 ;;
    --gui) GUI=(--gui); shift ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
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
NAME="$(basename "$WORLD" .xml)"
echo "demo: exploring $WORLD with doors $CLOSED closed, then predicting with '$METHOD' (a few minutes)"
status=0
rosrun hidden_rooms explore_worlds "$WORLD" --out "$OUT" --closed "$CLOSED" --method "$METHOD" "${GUI[@]}" || status=$?
RUN="$OUT/$NAME"
if [ "$status" -ne 0 ] || [ ! -f "$RUN/prediction/metrics.yaml" ]; then
  echo "demo: the run failed; see $RUN/launch.log and $RUN/worker.log" >&2
  exit 1
fi
cat <<MSG
demo: written
  $RUN/map.yaml              the map the robot built (the rooms behind the closed doors unknown)
  $RUN/doors.yaml            the closed doors, translated into the map frame
  $RUN/prediction/map.yaml   the map completed with the predicted rooms, their doors opened
  $RUN/overlay.png           predicted rooms tinted, true rooms outlined green, trajectory blue, doors red
  $RUN/prediction/metrics.yaml  IoU per room, mean IoU, IoU_tot
  $RUN/exploration.yaml      coverage, map quality, path length, door translation errors
  $RUN/poses_map.log, poses_truth.log   the estimated and true trajectories (0.1 s)
MSG
grep -E "door_id|mean_iou" "$RUN/prediction/metrics.yaml" | sed 's/^/  /'
