#!/usr/bin/env bash
# Fuzzes every reader of the core with libFuzzer (clang, AddressSanitizer + UndefinedBehaviorSanitizer):
# environment XML, map yaml + image, images, doors.yaml, the prediction parameters file, pose logs and OctoMap
# files. Builds the targets in .ws/build_fuzz, seeds each corpus from test/fuzz/regressions/TARGET, the shipped
# worlds and configs and the shared data (when ../shared is there), runs each target for SECONDS (default 600)
# and prints its executions and time. A crash, hang (> 10 s per input) or memory blow-up (> 2 GB) is kept in
# .fuzz/artifacts/TARGET/ and makes the script exit 1; copy it to test/fuzz/regressions/TARGET/ once fixed.
#   scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="/usr/bin:$PATH"
SECONDS_PER_TARGET="${1:-600}"
shift || true
ALL_TARGETS=(environment_xml map_yaml image doors_yaml parameter_file pose_log octomap)
TARGETS=("${@:-${ALL_TARGETS[@]}}")
WS="$ROOT/.ws"
FUZZ="$ROOT/.fuzz"
SHARED="$ROOT/../shared/data"

bash "$ROOT/scripts/setup.sh" > /dev/null
# shellcheck disable=SC1091
set +u && source "$WS/devel/setup.bash" && set -u
mkdir -p "$FUZZ"
cd "$WS"
# Its own build and devel folders with clang (the main build stays gcc).
catkin_make --build build_fuzz -DCATKIN_DEVEL_PREFIX="$WS/devel_fuzz" -DHIDDEN_ROOMS_FUZZ=ON \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCATKIN_ENABLE_TESTING=OFF -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  -j"$(nproc)" "${TARGETS[@]/#/fuzz_}" > "$FUZZ/build.log" 2>&1 || { tail -30 "$FUZZ/build.log"; exit 1; }

# Seeds: the kept inputs, then real files of each kind.
seed() {  # seed TARGET FILE... (nothing when TARGET is not fuzzed this time)
  local dir="$FUZZ/corpus/$1"; shift
  [ -d "$dir" ] || return 0
  for file in "$@"; do [ -f "$file" ] && cp "$file" "$dir/seed_$(basename "$(dirname "$file")")_$(basename "$file")"; done
  return 0
}
for target in "${TARGETS[@]}"; do
  mkdir -p "$FUZZ/corpus/$target" "$FUZZ/artifacts/$target"
  cp "$ROOT/test/fuzz/regressions/$target/"* "$FUZZ/corpus/$target/" 2>/dev/null || true
done
seed environment_xml "$ROOT"/worlds/*.xml $(ls "$SHARED"/environments/*/*.xml 2>/dev/null | head -20)
seed doors_yaml $(ls "$SHARED"/closed_door_benchmark/*/*/doors.yaml 2>/dev/null | head -10)
seed parameter_file "$ROOT/config/prediction.yaml" "$ROOT/config/layout.yaml"
seed image $(ls "$SHARED"/closed_door_benchmark/*/*/gt_rooms.png 2>/dev/null | head -3)
# Rendered small worlds: "yaml \0 image" pairs, their images and their OctoMaps ("\0" + a .bt).
if [ -d "$FUZZ/corpus/map_yaml" ] || [ -d "$FUZZ/corpus/image" ] || [ -d "$FUZZ/corpus/octomap" ]; then
  for world in "$ROOT"/worlds/small_*.xml; do
    name="$(basename "$world" .xml)"
    out="$FUZZ/render_$name"
    rosrun hidden_rooms render_environment "$world" --out "$out" --resolution 0.2 > /dev/null
    if [ -d "$FUZZ/corpus/map_yaml" ]; then
      { sed 's/^image: .*/image: map.img/' "$out/map.yaml"; printf '\0'; cat "$out/map.pgm"; } \
        > "$FUZZ/corpus/map_yaml/seed_$name"
    fi
    seed image "$out/map.pgm"
    if [ -d "$FUZZ/corpus/octomap" ]; then
      rosrun hidden_rooms export_octomap "$out/map.yaml" --out "$out/map.bt" --height 0.6 > /dev/null
      { printf '\0'; cat "$out/map.bt"; } > "$FUZZ/corpus/octomap/seed_${name}_bt"
    fi
  done
fi
if [ -d "$FUZZ/corpus/pose_log" ]; then
  printf '# frame: map -> base_link\n0.1000 1.0 2.0 0.5\n0.2000 1.1 2.0 0.6\n' > "$FUZZ/corpus/pose_log/seed_log"
fi

failed=0
printf '%-16s %12s %8s %s\n' target executions seconds result
for target in "${TARGETS[@]}"; do
  log="$FUZZ/$target.log"
  start=$(date +%s)
  status=0
  # The instrumented core library, not the main build's that devel/setup.bash puts on LD_LIBRARY_PATH.
  (cd "$FUZZ" && LD_LIBRARY_PATH="$WS/devel_fuzz/lib:${LD_LIBRARY_PATH:-}" \
     "$WS/devel_fuzz/lib/hidden_rooms/fuzz_$target" "$FUZZ/corpus/$target" \
     -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
     -close_fd_mask=1 -artifact_prefix="$FUZZ/artifacts/$target/" > "$log" 2>&1) || status=$?
  executions=$(grep -aoP 'stat::number_of_executed_units:\s*\K[0-9]+' "$log" || echo "?")
  result=ok
  if [ "$status" -ne 0 ]; then result="FAILED (see $log and $FUZZ/artifacts/$target/)"; failed=1; fi
  printf '%-16s %12s %8s %s\n' "$target" "$executions" "$(( $(date +%s) - start ))" "$result"
done
exit "$failed"
