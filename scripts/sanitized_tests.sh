#!/usr/bin/env bash
# Runs the ROS-free unit tests and the bus node (node_devices.test) built with ASan + UBSan
# (clang++: the instrumented build of scripts/instrumented_mode.sh, which has the fuzz targets
# too); JUnit results go to RESULTS.
#   sanitized_tests.sh RESULTS               build, then run
#   sanitized_tests.sh --build-only          build only, the fuzz targets too (test.sh builds while
#                                            the rostests run)
#   sanitized_tests.sh --prebuilt RESULTS    run what --build-only built (its failure counts)
set -euo pipefail
# shellcheck source=SCRIPTDIR/instrumented_mode.sh
source "$(dirname "$0")/instrumented_mode.sh"  # MODE, REPO, WS, BUILD, instrumented_build
RESULTS=${1:-}
if [ $MODE != run ]; then
  # shellcheck disable=SC2119  # every target
  instrumented_build || true  # its failure fails the run below
  [ $MODE = build ] && exit 0
fi
mkdir -p "$BUILD/logs"
[ -n "$RESULTS" ] || { echo "usage: $0 [--build-only | --prebuilt] RESULTS" >&2; exit 2; }
mkdir -p "$RESULTS"
status=0
junit() {  # suite (and file name), case: NAME or NAME=FAILURE (scripts/junit.py)
  /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/$1.xml" "$1" --classname sanitizers "$2"
}
# A build that fails (or never ran) must fail the run: old binaries would otherwise be tested
# as if new.
if [ "$(cat "$SANITIZERS_STATUS" 2>/dev/null)" != ok ]; then
  grep -E "Error" "$BUILD/logs/configure.log" 2>/dev/null | head -5 || true
  grep -E "error|warning: " "$BUILD/logs/build.log" 2>/dev/null | head -20 || true
  junit sanitized-build "build=the instrumented build failed (or built the fuzz targets only), see $BUILD/logs/build.log"
  exit 1
fi
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1
# The tests cmake/unit_tests.cmake lists (ctest knows them), not whatever test_* an older build
# left in the folder; one that is listed but missing fails.
tests=$(cd "$BUILD" && ctest -N | sed -n 's/^ *Test *#[0-9]*: *//p')
[ -n "$tests" ] || { junit sanitized-build "build=ctest lists no test in $BUILD"; exit 1; }
for name in $tests; do
  t=$BUILD/$name
  echo "sanitized: $name"
  "$t" --gtest_output="xml:$RESULTS/sanitized-$name.xml" >"$BUILD/logs/$name.log" 2>&1 || {
    status=1
    tail -30 "$BUILD/logs/$name.log"
    # A sanitizer report aborts the binary before gtest writes its XML: record the failure.
    [ -s "$RESULTS/sanitized-$name.xml" ] ||
      junit "sanitized-$name" "$name=sanitizer report, crash or no binary, see $BUILD/logs/$name.log"
  }
  if grep -qE "ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:" "$BUILD/logs/$name.log"; then
    echo "sanitizer report in $name"; status=1
  fi
done

# The node itself under the sanitizers: node_devices.test (every service and topic of the three
# device types) with the sanitized build of modbus_rtu_bus in place of the normal one.
node_case() {  # name, failure message or "" -> one JUnit case
  junit sanitized-node "$1${2:+=$2}"
}
set +u
# shellcheck disable=SC1091
source "$WS/devel/setup.bash"  # rostest must find the package (test.sh has it already)
set -u
export SANITIZED_NODE="$BUILD/modbus_rtu_bus"
rm -f "$BUILD"/logs/node.* "$SANITIZED_NODE.started"
if [ -x "$SANITIZED_NODE" ]; then
  echo "sanitized: rostest node_devices.test with $SANITIZED_NODE"
  ASAN_OPTIONS="detect_leaks=1:log_path=$BUILD/logs/node" UBSAN_OPTIONS="print_stacktrace=1:log_path=$BUILD/logs/node" \
    LSAN_OPTIONS="suppressions=$REPO/test/sanitizers/lsan.supp:print_suppressions=0" \
    ROS_TEST_RESULTS_DIR="$RESULTS/node" /usr/bin/python3 "$REPO/test/run_rostest.py" \
    "$REPO/test/rostest/node_devices.test" node_prefix:="$REPO/test/sanitizers/node_prefix.sh" \
    >"$BUILD/logs/node_rostest.log" 2>&1 || status=1
  if [ ! -e "$SANITIZED_NODE.started" ]; then
    node_case node_rostest_under_sanitizers "the sanitized node never started"; status=1
  elif cat "$BUILD"/logs/node.* 2>/dev/null | grep -qE "ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:"; then
    node_case node_rostest_under_sanitizers "sanitizer report, see $BUILD/logs/node.*"; status=1
    cat "$BUILD"/logs/node.* | head -40
  else
    node_case node_rostest_under_sanitizers_zero_reports ""
  fi
else
  node_case node_rostest_under_sanitizers "no sanitized node was built"; status=1
fi
exit $status
