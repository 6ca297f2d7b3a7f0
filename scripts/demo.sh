#!/usr/bin/env bash
# Installs what is missing, builds, starts the simulator and the bus node (demo.launch) and shows
# live state: relay and input states, PWM and PDU telemetry. Ctrl-C stops it.
# Options: --duration S (stop after S seconds), --record (also record a bag under .build/bags).
source "$(dirname "$0")/common.sh"
DURATION=0
LAUNCH_ARGS=()
while (($#)); do
  case "$1" in
    --duration) DURATION=$2; shift 2 ;;
    --record) mkdir -p "$REPO/.build/bags"; LAUNCH_ARGS+=(record:=true "bag:=$REPO/.build/bags/demo"); shift ;;
    *) echo "usage: $0 [--duration SECONDS] [--record]" >&2; exit 2 ;;
  esac
done
install_deps
build_workspace
export ROS_MASTER_URI=${ROS_MASTER_URI:-http://localhost:11311}

mkdir -p "$REPO/.build"
LOG=$REPO/.build/demo.log
roslaunch modbus_rtu_driver demo.launch "${LAUNCH_ARGS[@]}" >"$LOG" 2>&1 &
LAUNCH_PID=$!
cleanup() { kill -INT "$LAUNCH_PID" 2>/dev/null; wait "$LAUNCH_PID" 2>/dev/null || true; }
trap cleanup EXIT INT TERM

echo "waiting for the bus node (log: $LOG) ..."
for _ in $(seq 60); do
  rosservice list 2>/dev/null | grep -q /modbus_bus/relays/pump/set && break
  sleep 0.5
done
rosservice list 2>/dev/null | grep -q /modbus_bus/relays/pump/set || { echo "bus node did not start:"; tail -20 "$LOG"; exit 1; }

show() { echo; echo "\$ $*"; "$@"; }
show rosservice call /modbus_bus/relays/pump/set "data: true"
show rostopic echo -n 1 /modbus_bus/relays/outputs
show rosservice call /modbus_bus/pwm_board/set_pwm "{channel: 0, period: 1.0, on_time: 0.5, pulses: 0}"
show rostopic echo -n 1 /modbus_bus/pdu/telemetry
echo
echo "live state (Ctrl-C to stop): /modbus_bus/relays/outputs and /modbus_bus/pdu/telemetry"
if [ "$DURATION" != 0 ]; then
  timeout "$DURATION" rostopic echo /modbus_bus/pdu/telemetry || true
else
  rostopic echo /modbus_bus/pdu/telemetry
fi
