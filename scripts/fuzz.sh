#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, with ASan + UBSan) and runs each for SECONDS (default 20).
# A longer run by hand: scripts/fuzz.sh 3600. With RESULTS_DIR, writes a JUnit result there.
#   fuzz.sh --build-only                  build only (test.sh builds while the rostests run)
#   fuzz.sh --prebuilt SECONDS RESULTS    run what --build-only built
set -euo pipefail
# shellcheck source=SCRIPTDIR/instrumented_mode.sh
source "$(dirname "$0")/instrumented_mode.sh"  # MODE from --build-only / --prebuilt; REPO, WS
SECONDS_TO_RUN=${1:-20}
RESULTS=${2:-}
OUT="$WS/fuzz"
mkdir -p "$OUT/corpus"
# Three targets (test/fuzz/; what each feeds: test/sanitizers/CMakeLists.txt), built by the
# instrumented CMake build with -DMODBUS_RTU_FUZZ=ON against the layer libraries of
# cmake/layers.cmake, the same sources as every other build.
BUILD="$OUT/build"
TARGETS=(fuzz_frames fuzz_slave fuzz_share)
if [ $MODE != run ]; then
  mkdir -p "$BUILD"
  rm -f "${TARGETS[@]/#/$OUT/}"
  # Each target on its own: one that does not build is run as missing below, and fails.
  if cmake -S "$REPO/test/sanitizers" -B "$BUILD" -DCMAKE_CXX_COMPILER=clang++ -DMODBUS_RTU_FUZZ=ON \
    -DCMAKE_RUNTIME_OUTPUT_DIRECTORY="$OUT" >"$BUILD/configure.log" 2>&1; then
    for name in "${TARGETS[@]}"; do
      cmake --build "$BUILD" --target "$name" -j"$(nproc)" >"$BUILD/$name.build.log" 2>&1 ||
        { tail -20 "$BUILD/$name.build.log"; echo "$name: build failed"; }
    done
  else
    tail -20 "$BUILD/configure.log"; echo "fuzz build: configure failed"
  fi
fi
[ $MODE = build ] && exit 0
# Seed with the manuals' frames.
grep -v '^#' "$REPO/test/data/golden_frames.tsv" | tail -n +2 | cut -f4 | while read -r hex; do
  printf '%s' "$hex" | xxd -r -p >"$OUT/corpus/$(printf '%s' "$hex" | md5sum | cut -c1-12)"
done || true
# And with every input that once broke a target (test/fuzz/regressions), so it is run again.
cp "$REPO"/test/fuzz/regressions/* "$OUT/corpus/"
overall=0
for name in "${TARGETS[@]}"; do
  status=0
  mkdir -p "$OUT/corpus-$name"
  if [ -x "$OUT/$name" ]; then
    # A crashing input is kept beside the target (its log names it), never in the caller's folder.
    "$OUT/$name" -max_total_time="$SECONDS_TO_RUN" -print_final_stats=1 \
      -artifact_prefix="$OUT/$name-" "$OUT/corpus-$name" "$OUT/corpus" >"$OUT/$name.log" 2>&1 ||
      status=$?
  else
    echo "$name was not built" >"$OUT/$name.log"
    status=127
  fi
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$OUT/$name.log" | grep -oE '[0-9]+$' || echo 0)
  echo "$name: $runs inputs in ${SECONDS_TO_RUN} s, exit $status"
  [ $status = 0 ] || { tail -40 "$OUT/$name.log"; overall=1; }
  if [ -n "$RESULTS" ]; then
    mkdir -p "$RESULTS"
    if [ $status = 0 ]; then
      /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/$name.xml" fuzz "${name}_${runs}_inputs"
    else
      /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/$name.xml" fuzz \
        "$name=not built, crash or invariant broken, see $OUT/$name.log"
    fi
  fi
done
exit $overall
