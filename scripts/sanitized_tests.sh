#!/usr/bin/env bash
# Builds the ROS-free unit tests with ASan + UBSan and runs them; JUnit results go to $1.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
RESULTS=$1
BUILD="$("$REPO/scripts/workspace.sh")/sanitizers"
mkdir -p "$BUILD" "$RESULTS"
cmake -S "$REPO/test/sanitizers" -B "$BUILD" -DCMAKE_CXX_COMPILER=g++ >/dev/null
cmake --build "$BUILD" -j"$(nproc)" 2>&1 | grep -E "error|warning: " || true
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1
status=0
mkdir -p "$BUILD/logs"
for t in "$BUILD"/test_*; do
  [ -f "$t" ] && [ -x "$t" ] || continue
  name=$(basename "$t")
  echo "sanitized: $name"
  "$t" --gtest_output="xml:$RESULTS/sanitized-$name.xml" >"$BUILD/logs/$name.log" 2>&1 || {
    status=1
    tail -30 "$BUILD/logs/$name.log"
    # A sanitizer report aborts the binary before gtest writes its XML: record the failure.
    [ -s "$RESULTS/sanitized-$name.xml" ] || printf '<testsuite name="sanitized-%s" tests="1" failures="1"><testcase classname="sanitizers" name="%s"><failure message="sanitizer report or crash, see %s"/></testcase></testsuite>\n' "$name" "$name" "$BUILD/logs/$name.log" >"$RESULTS/sanitized-$name.xml"
  }
  if grep -qE "ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:" "$BUILD/logs/$name.log"; then
    echo "sanitizer report in $name"; status=1
  fi
done
exit $status
