#!/usr/bin/env bash
# Builds the libFuzzer target (clang, with ASan + UBSan) and runs it for SECONDS (default 20).
# A longer run by hand: scripts/fuzz.sh 3600. With RESULTS_DIR, writes a JUnit result there.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
SECONDS_TO_RUN=${1:-20}
RESULTS=${2:-}
OUT="$("$REPO/scripts/workspace.sh")/fuzz"
mkdir -p "$OUT/corpus"
SRC=(test/fuzz/fuzz_frames.cpp src/core/frame.cpp src/core/types.cpp src/core/request_framer.cpp
  src/sim/sim_device.cpp src/sim/sim_ld58a08.cpp src/sim/sim_lc_relay8.cpp src/sim/sim_yespeed_pdu.cpp)
(cd "$REPO" && clang++ -std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined \
  -fno-sanitize-recover=all -Iinclude "${SRC[@]}" -lyaml-cpp -o "$OUT/fuzz_frames")
# Seed with the manuals' frames.
grep -v '^#' "$REPO/../shared/golden-frames.tsv" 2>/dev/null | tail -n +2 | cut -f4 | while read -r hex; do
  printf '%s' "$hex" | xxd -r -p >"$OUT/corpus/$(printf '%s' "$hex" | md5sum | cut -c1-12)"
done || true
status=0
"$OUT/fuzz_frames" -max_total_time="$SECONDS_TO_RUN" -print_final_stats=1 "$OUT/corpus" \
  >"$OUT/fuzz.log" 2>&1 || status=$?
runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$OUT/fuzz.log" | grep -oE '[0-9]+$' || echo 0)
echo "fuzz_frames: $runs inputs in ${SECONDS_TO_RUN} s, exit $status"
[ $status = 0 ] || tail -40 "$OUT/fuzz.log"
if [ -n "$RESULTS" ]; then
  mkdir -p "$RESULTS"
  if [ $status = 0 ]; then
    printf '<testsuite name="fuzz" tests="1"><testcase classname="fuzz" name="fuzz_frames_%s_inputs"/></testsuite>\n' "$runs" >"$RESULTS/fuzz-frames.xml"
  else
    printf '<testsuite name="fuzz" tests="1" failures="1"><testcase classname="fuzz" name="fuzz_frames"><failure message="crash or invariant broken, see %s"/></testcase></testsuite>\n' "$OUT/fuzz.log" >"$RESULTS/fuzz-frames.xml"
  fi
fi
exit $status
