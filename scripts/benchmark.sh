#!/usr/bin/env bash
# Installs what is missing, builds, and runs the benchmark; writes bench/results.md and
# bench/results.csv. Usage: scripts/benchmark.sh [SECONDS_PER_CELL]
source "$(dirname "$0")/common.sh"
install_deps
build_workspace
"$WS/devel/lib/modbus_rtu_driver/modbus_rtu_benchmark" --seconds "${1:-2}" \
  --csv "$REPO/bench/results.csv" | tee "$REPO/bench/results.md"
