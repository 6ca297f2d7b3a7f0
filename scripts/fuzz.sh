#!/usr/bin/env bash
# Builds the libFuzzer targets (clang++, ASan + UBSan: the instrumented build of
# scripts/instrumented_mode.sh, which sanitized_tests.sh runs from too) and runs them, all at once, for SECONDS
# (default 20). A longer run by hand: scripts/fuzz.sh 3600 (builds the fuzz targets only). With
# RESULTS_DIR, writes a JUnit result there.
#   fuzz.sh --build-only                  build only, the sanitized tests and node too (test.sh
#                                         builds while the rostests run)
#   fuzz.sh --prebuilt SECONDS RESULTS    run what --build-only built
set -euo pipefail
# shellcheck source=SCRIPTDIR/instrumented_mode.sh
source "$(dirname "$0")/instrumented_mode.sh"  # MODE, REPO, WS, BUILD, instrumented_build
SECONDS_TO_RUN=${1:-20}
RESULTS=${2:-}
OUT="$WS/fuzz"  # logs, corpora, crashing inputs
mkdir -p "$OUT/corpus"
# Three targets (test/fuzz/; what each feeds: test/sanitizers/CMakeLists.txt), in the instrumented
# build against the layer libraries of cmake/layers.cmake, the same sources as every other build.
# The build deletes them first and goes on past an error: one that does not build is run as
# missing below, and fails.
TARGETS=("${FUZZ_TARGETS[@]}")
if [ $MODE = build ]; then
  # shellcheck disable=SC2119  # every target
  instrumented_build || true
elif [ $MODE = all ]; then
  instrumented_build "${TARGETS[@]}" || true
fi
[ $MODE = build ] && exit 0
# Seed with the manuals' frames.
grep -v '^#' "$REPO/test/data/golden_frames.tsv" | tail -n +2 | cut -f4 | while read -r hex; do
  printf '%s' "$hex" | xxd -r -p >"$OUT/corpus/$(printf '%s' "$hex" | md5sum | cut -c1-12)"
done || true
# And with every input that once broke a target (test/fuzz/regressions), so it is run again.
cp "$REPO"/test/fuzz/regressions/* "$OUT/corpus/"
# The targets run at the same time (each -max_total_time=SECONDS, one process each: on 2 cores,
# three for 22 s get about the CPU that one after another for 15 s each had); then each one's
# result, in order.
declare -A status
for name in "${TARGETS[@]}"; do
  mkdir -p "$OUT/corpus-$name"
  if [ -x "$BUILD/$name" ]; then
    # A crashing input is kept beside the target (its log names it), never in the caller's folder.
    "$BUILD/$name" -max_total_time="$SECONDS_TO_RUN" -print_final_stats=1 \
      -artifact_prefix="$OUT/$name-" "$OUT/corpus-$name" "$OUT/corpus" >"$OUT/$name.log" 2>&1 &
    status[$name]=$!
  else
    echo "$name was not built" >"$OUT/$name.log"
    status[$name]=missing
  fi
done
overall=0
for name in "${TARGETS[@]}"; do
  if [ "${status[$name]}" = missing ]; then
    rc=127
  else
    rc=0
    wait "${status[$name]}" || rc=$?
  fi
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$OUT/$name.log" | grep -oE '[0-9]+$' || echo 0)
  echo "$name: $runs inputs in ${SECONDS_TO_RUN} s, exit $rc"
  [ $rc = 0 ] || { tail -40 "$OUT/$name.log"; overall=1; }
  if [ -n "$RESULTS" ]; then
    mkdir -p "$RESULTS"
    if [ $rc = 0 ]; then
      /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/$name.xml" fuzz "${name}_${runs}_inputs"
    else
      /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/$name.xml" fuzz \
        "$name=not built, crash or invariant broken, see $OUT/$name.log"
    fi
  fi
done
exit $overall
