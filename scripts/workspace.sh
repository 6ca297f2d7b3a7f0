#!/usr/bin/env bash
# Prints the path of this checkout's catkin workspace (built by demo.sh / test.sh / build.sh).
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
echo "${MODBUS_RTU_WS:-${XDG_CACHE_HOME:-$HOME/.cache}/modbus_rtu_driver/ws-$(printf %s "$REPO" | md5sum | cut -c1-8)}"
