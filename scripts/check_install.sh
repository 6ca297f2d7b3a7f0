#!/usr/bin/env bash
# Installs the package (catkin_make install) and checks that the install space works on its
# own: the package is found, the launch files resolve, the scripts the docs use are installed,
# and the installed simulator and commissioning tool run (a scan finds the three simulated
# devices; the scan starts once the simulator's link exists, waited for up to 10 s). Writes a
# JUnit case to $1.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
WS=$("$REPO/scripts/workspace.sh")
RESULTS=$1
mkdir -p "$RESULTS"
LOG="$WS/check_install.log"
(cd "$WS" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 install) >"$LOG" 2>&1
check() {
  # A clean environment: only Debian's ROS and the install space, not the devel space.
  env -i HOME="$HOME" PATH=/usr/bin:/bin bash -c "source '$WS/install/setup.bash' && $1" >>"$LOG" 2>&1
}
problem=""
check 'rospack find modbus_rtu_driver | grep -q "/install/share/modbus_rtu_driver$"' ||
  problem="rospack does not find the installed package"
[ -n "$problem" ] || check 'roslaunch --files modbus_rtu_driver demo.launch | grep -q bus.launch' ||
  problem="demo.launch does not resolve from the install space"
# The scripts the docs run with rosrun (issue 33 item 4: test/sim_control.py was not installed).
for script in sim_control.py plot_bag.py bus_record.py; do
  [ -n "$problem" ] || check "BIN=\$(catkin_find --first-only --libexec modbus_rtu_driver $script) &&
    case \$BIN in */install/*) ;; *) exit 1;; esac && test -x \$BIN" ||
    problem="$script is not installed"
done
if [ -z "$problem" ]; then
  dir=$(mktemp -d)
  check "cd / && BIN=\$(catkin_find --first-only --libexec modbus_rtu_driver modbus_rtu_simulator) &&
    case \$BIN in */install/*) ;; *) exit 1;; esac &&
    { \$BIN --config \$(rospack find modbus_rtu_driver)/config/simulator.yaml --link $dir/tty & } &&
    { for _ in \$(seq 100); do [ -e $dir/tty ] && break; sleep 0.1; done; } &&
    rosrun modbus_rtu_driver modbus_rtu_commission --port $dir/tty scan --addresses 1,2,8 \
      > $dir/scan.txt; status=\$?; kill %1; exit \$status" ||
    problem="the installed simulator or commissioning tool failed"
  [ -n "$problem" ] || [ "$(grep -cE 'lc_relay8|ld58a08|yespeed_pdu' "$dir/scan.txt")" -ge 3 ] ||
    problem="the installed tool's scan did not find the three simulated devices"
  cat "$dir/scan.txt" >>"$LOG" 2>/dev/null || true
  rm -rf "$dir"
fi
if [ -z "$problem" ]; then
  echo "install space: ok"
  /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/install.xml" install install_space_works
else
  echo "install space: $problem (see $LOG)"
  /usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/install.xml" install \
    "install_space_works=$problem, see $LOG"
  exit 1
fi
