#!/usr/bin/env bash
# Runs every test of hidden_rooms: sets up and builds (scripts/setup.sh), runs the gtest unit tests, rostests,
# Python tests and launch-file checks through `catkin_make run_tests`, then builds the core's unit tests with
# AddressSanitizer + UndefinedBehaviorSanitizer and runs them. Exits non-zero when any test fails.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ROS 1 on Debian runs on Debian's Python: keep /usr/bin ahead of any other python3 on PATH.
export PATH="/usr/bin:$PATH"
WS="$ROOT/.ws"
JOBS="$(nproc)"

bash "$ROOT/scripts/setup.sh"
# shellcheck disable=SC1091
set +u && source "$WS/devel/setup.bash" && set -u

# With the shared data folder beside the checkout, tests that read it must not skip.
if [ -d "$ROOT/../shared/data" ]; then
  export HIDDEN_ROOMS_SHARED_DIR="$(cd "$ROOT/../shared" && pwd)"
  export HIDDEN_ROOMS_REQUIRE_SHARED=1
fi

cd "$WS"
rm -rf build/test_results
catkin_make run_tests -j"$JOBS"

# Sanitizer build of the core and its unit tests, in its own build and devel folders.
catkin_make --build build_sanitize -DCATKIN_DEVEL_PREFIX="$WS/devel_sanitize" -DHIDDEN_ROOMS_SANITIZE=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  -j"$JOBS" test_core
mkdir -p build/test_results/hidden_rooms
sanitized_status=0
ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  "$WS/devel_sanitize/lib/hidden_rooms/test_core" \
  --gtest_output=xml:"$WS/build/test_results/hidden_rooms/gtest-test_core_sanitized.xml" || sanitized_status=$?

summary="$(catkin_test_results build/test_results || true)"
echo "$summary"
# One closing line: "tests: N passed, N failed, N skipped".
read -r total errors failures skipped < <(echo "$summary" | sed -n \
  's/^Summary: \([0-9]*\) tests, \([0-9]*\) errors, \([0-9]*\) failures, \([0-9]*\) skipped.*/\1 \2 \3 \4/p')
failed=$((errors + failures))
if [ "$sanitized_status" -ne 0 ] && [ "$failed" -eq 0 ]; then
  failed=1  # the sanitized run died before writing its report
fi
echo "tests: $((total - errors - failures - skipped)) passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$sanitized_status" -eq 0 ]
