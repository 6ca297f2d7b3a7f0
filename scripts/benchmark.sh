#!/usr/bin/env bash
# Installs what is missing, builds, and runs the benchmark (a script, not a test): the bus layer
# against plain libmodbus and pymodbus, line utilisation, 1-32 devices (modbus_rtu_benchmark),
# then where the line's time goes (bench/line_attribution.py: wire, silences, the simulator's
# and the driver's turnaround, and beside them a bare thread's wake-up lateness from
# modbus_rtu_wakeup_probe, the machine's share), the node's latency and CPU use against the CPU
# a bare thread waking as often costs (bench/node_bench.py, its own
# rosmaster), the latency of a request through the node's Modbus TCP share
# (bench/share_bench.py), where the node's CPU goes, from perf's samples
# (bench/profile_node.py), and 1, 2, 4 and 8 buses on one machine, a node and a simulator each
# (bench/multi_bus_bench.py: CPU per node and in all, polls held, SetBool latency). Each node
# figure is the median (lowest-highest) of 5 runs (3 for the buses' rows). Writes
# bench/results.md and bench/results.csv. Usage: scripts/benchmark.sh [SECONDS_PER_CELL]
#   scripts/benchmark.sh --smoke DIR   the test command's smoke run (about 100 s, the workspace
#   built): every benchmark program with the least work it takes (1 and 2 buses for
#   multi_bus_bench.py), its tables and CSV into DIR,
#   one JUnit case per program in DIR/bench_smoke.xml, failed when it exits nonzero or prints no
#   table. No figure is asserted: it proves that the benchmark still runs to its end.
source "$(dirname "$0")/common.sh"
if [ "${1:-}" = "--smoke" ]; then
  out=${2:?--smoke needs a folder}
  set +u
  # shellcheck disable=SC1091
  source "$WS/devel/setup.bash"
  set -u
  mkdir -p "$out"
  rm -f "$out/results.csv"
  cases=() skipped=()
  smoke() {  # NAME COMMAND...
    local name=$1 rc=0
    shift
    "$@" --csv "$out/results.csv" >"$out/$name.md" 2>"$out/$name.err" || rc=$?
    if [ "$rc" = 0 ] && grep -q '^|' "$out/$name.md"; then
      cases+=("$name")
    elif [ "$rc" = 77 ]; then  # the program says why it cannot measure here (no perf for this kernel)
      skipped+=(--skipped "$name=$(tail -n 1 "$out/$name.err")")
    else
      tail -n 20 "$out/$name.md" "$out/$name.err" >"$out/$name.fail"
      cases+=("$name=@$out/$name.fail")
    fi
    cat "$out/$name.md"
  }
  smoke benchmark "$WS/devel/lib/modbus_rtu_driver/modbus_rtu_benchmark" --seconds 0.1 --smoke
  smoke line_attribution /usr/bin/python3 "$REPO/bench/line_attribution.py" --seconds 1 \
    --repeats 1 --bauds 115200
  smoke node_bench /usr/bin/python3 "$REPO/bench/node_bench.py" --calls 20 --repeats 1 --hog 0 \
    --cpu-seconds 1 --bauds 115200
  smoke share_bench /usr/bin/python3 "$REPO/bench/share_bench.py" --requests 20 --bauds 115200
  smoke profile_node /usr/bin/python3 "$REPO/bench/profile_node.py" --seconds 2
  smoke multi_bus_bench /usr/bin/python3 "$REPO/bench/multi_bus_bench.py" --buses 1,2 \
    --seconds 2 --settle 1 --calls 10 --repeats 1
  exec /usr/bin/python3 "$REPO/scripts/junit.py" "$out/bench_smoke.xml" bench_smoke \
    "${skipped[@]}" "${cases[@]}"
fi
install_deps
build_workspace >/dev/null
rm -f "$REPO/bench/results.csv"
{
  "$WS/devel/lib/modbus_rtu_driver/modbus_rtu_benchmark" --seconds "${1:-2}" \
    --csv "$REPO/bench/results.csv"
  /usr/bin/python3 "$REPO/bench/line_attribution.py" --seconds 5 --repeats 5 --realtime 50 \
    --csv "$REPO/bench/results.csv" 2> >(grep -v "^modbus_rtu_simulator\|wait_for_service" >&2)
  /usr/bin/python3 "$REPO/bench/node_bench.py" --calls 300 --repeats 5 --hog "$(nproc)" --cpu-seconds 10 \
    --csv "$REPO/bench/results.csv" 2> >(grep -v "^modbus_rtu_simulator\|wait_for_service" >&2)
  /usr/bin/python3 "$REPO/bench/share_bench.py" --requests 300 \
    --csv "$REPO/bench/results.csv" 2> >(grep -v "^modbus_rtu_simulator\|wait_for_service" >&2)
  /usr/bin/python3 "$REPO/bench/profile_node.py" --seconds 20 \
    --csv "$REPO/bench/results.csv" 2> >(grep -v "^modbus_rtu_simulator\|wait_for_service" >&2)
  /usr/bin/python3 "$REPO/bench/multi_bus_bench.py" --buses 1,2,4,8 --seconds 10 --calls 300 \
    --repeats 3 --csv "$REPO/bench/results.csv" \
    2> >(grep -v "^modbus_rtu_simulator\|wait_for_service" >&2)
} | tee "$REPO/bench/results.md"
