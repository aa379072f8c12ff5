#!/usr/bin/env bash
# Runs every test of hidden_rooms: sets up and builds (scripts/setup.sh), runs the gtest unit tests, rostests,
# Python tests and launch-file checks through `catkin_make run_tests`, installs (.ws/install) and tests the install
# space (test/install/), then builds the core's unit tests with
# AddressSanitizer + UndefinedBehaviorSanitizer and runs them, and runs every fuzz target for 20 s
# (HIDDEN_ROOMS_FUZZ_SECONDS). Exits non-zero when any test fails.
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

# The install space (.ws/install) on its own: programs, launch files, the demo's prediction, a downstream package.
catkin_make install -j"$JOBS" >"$WS/build/install.log" 2>&1 || { tail -50 "$WS/build/install.log"; exit 1; }
mkdir -p build/test_results/hidden_rooms
install_status=0
HIDDEN_ROOMS_INSTALL_SPACE="$WS/install" /usr/bin/python3 -m nose -v "$ROOT/test/install/test_install_space.py" \
  --with-xunit --xunit-file="$WS/build/test_results/hidden_rooms/nosetests-test_install_space.xml" ||
  install_status=$?

# Sanitizer build of the core and its unit tests (test_core_*), in its own build and devel folders.
catkin_make --build build_sanitize -DCATKIN_DEVEL_PREFIX="$WS/devel_sanitize" -DHIDDEN_ROOMS_SANITIZE=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  -j"$JOBS" hidden_rooms_core_tests
sanitized_status=0
for test_binary in "$WS"/devel_sanitize/lib/hidden_rooms/test_core_*; do
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 "$test_binary" \
    --gtest_output=xml:"$WS/build/test_results/hidden_rooms/gtest-$(basename "$test_binary")_sanitized.xml" ||
    sanitized_status=$?
done

# Every fuzz target briefly (scripts/fuzz.sh runs them as long as asked).
fuzz_status=0
bash "$ROOT/scripts/fuzz.sh" "${HIDDEN_ROOMS_FUZZ_SECONDS:-20}" || fuzz_status=$?
cd "$WS"

results_status=0
catkin_test_results build/test_results || results_status=$?
# Each failed test case with its failure messages (the first lines of each), then one closing line,
# "tests: N passed, N failed, N skipped", counted per test case from the result files (catkin_test_results counts
# gtest cases twice).
/usr/bin/python3 - build/test_results <<'PY'
import glob, os, sys
import xml.etree.ElementTree as ET
passed = failed = skipped = 0
for path in sorted(glob.glob(os.path.join(sys.argv[1], "**", "*.xml"), recursive=True)):
    root = ET.parse(path).getroot()
    cases = list(root.iter("testcase"))
    if not cases and root.get("failures", "0") != "0":
        failed += 1  # a MISSING-* report: the test never produced results
        print("FAILED %s: no results" % os.path.basename(path))
    for case in cases:
        problems = case.findall("failure") + case.findall("error")
        if problems:
            failed += 1
            print("FAILED %s: %s.%s" % (os.path.basename(path), case.get("classname"), case.get("name")))
            for problem in problems:
                text = (problem.get("message") or problem.text or "").strip().splitlines()
                print("\n".join("    " + line for line in text[:12]))
        elif case.find("skipped") is not None or case.get("status") == "notrun":
            skipped += 1
        else:
            passed += 1
print("tests: %d passed, %d failed, %d skipped" % (passed, failed, skipped))
PY
[ "$fuzz_status" -eq 0 ] || echo "fuzzing: FAILED (see .fuzz/)"
[ "$results_status" -eq 0 ] && [ "$sanitized_status" -eq 0 ] && [ "$fuzz_status" -eq 0 ] && [ "$install_status" -eq 0 ]
