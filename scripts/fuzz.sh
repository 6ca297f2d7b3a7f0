#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, with ASan + UBSan) and runs each for SECONDS (default 20).
# A longer run by hand: scripts/fuzz.sh 3600. With RESULTS_DIR, writes a JUnit result there.
#   fuzz.sh --build-only                  build only (test.sh builds while the rostests run)
#   fuzz.sh --prebuilt SECONDS RESULTS    run what --build-only built
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
MODE=all
case "${1:-}" in
  --build-only) MODE=build; shift ;;
  --prebuilt) MODE=run; shift ;;
esac
SECONDS_TO_RUN=${1:-20}
RESULTS=${2:-}
OUT="$("$REPO/scripts/workspace.sh")/fuzz"
mkdir -p "$OUT/corpus"
# Three targets: frames through the framer, decoder and simulated devices; the slave role's
# request handling (framer + libmodbus's modbus_reply on a real pty); and a Modbus TCP client's
# bytes at the share (ShareGateway on a loopback socket over a BusScheduler, test/unit's
# in-memory bus).
CORE=(src/core/frame.cpp src/core/types.cpp src/core/request_framer.cpp)
build() {  # a target that does not build is run as missing below, and fails
  local name=$1
  shift
  rm -f "$OUT/$name"
  (cd "$REPO" && clang++ -std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=all -Iinclude -Itest/unit -I/usr/include/modbus "test/fuzz/$name.cpp" "${CORE[@]}" "$@" \
    -lmodbus -lyaml-cpp -o "$OUT/$name") || echo "$name: build failed"
}
if [ $MODE != run ]; then
  build fuzz_frames src/sim/sim_device.cpp src/sim/sim_ld58a08.cpp src/sim/sim_lc_relay8.cpp \
    src/sim/sim_yespeed_pdu.cpp src/core/link_config.cpp
  build fuzz_slave src/core/slave_server.cpp src/core/serial_port.cpp src/core/fd_io.cpp \
    src/core/slave_config.cpp src/core/config_yaml.cpp src/core/link_config.cpp
  build fuzz_share src/core/share_gateway.cpp src/core/modbus_tcp_server.cpp \
    src/core/bus_scheduler.cpp src/core/mbap.cpp src/core/rate_meter.cpp -lpthread
fi
[ $MODE = build ] && exit 0
# Seed with the manuals' frames.
grep -v '^#' "$REPO/test/data/golden_frames.tsv" | tail -n +2 | cut -f4 | while read -r hex; do
  printf '%s' "$hex" | xxd -r -p >"$OUT/corpus/$(printf '%s' "$hex" | md5sum | cut -c1-12)"
done || true
# And with every input that once broke a target (test/fuzz/regressions), so it is run again.
cp "$REPO"/test/fuzz/regressions/* "$OUT/corpus/"
overall=0
for name in fuzz_frames fuzz_slave fuzz_share; do
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
      printf '<testsuite name="fuzz" tests="1"><testcase classname="fuzz" name="%s_%s_inputs"/></testsuite>\n' "$name" "$runs" >"$RESULTS/$name.xml"
    else
      printf '<testsuite name="fuzz" tests="1" failures="1"><testcase classname="fuzz" name="%s"><failure message="not built, crash or invariant broken, see %s"/></testcase></testsuite>\n' "$name" "$OUT/$name.log" >"$RESULTS/$name.xml"
    fi
  fi
done
exit $overall
