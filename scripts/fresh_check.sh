#!/usr/bin/env bash
# The fresh-machine proof (not part of the test command: it takes 20-30 minutes). For each of
# the README's two commands it builds a new bare Debian root with mmdebstrap (minbase: the
# Essential packages and apt), clones the committed repository into it alone (nothing beside it),
# and runs the command there as root:
#   demo: scripts/demo.sh --duration 20   passes when it printed live PDU telemetry;
#   test: scripts/test.sh                 passes when it ended "N passed, 0 failed"; then, in
#         the same root, scripts/tidy.sh: the whole clang-tidy pass with that release's
#         clang-tidy (11, 14, 19), which passes with 0 warnings (about 25 minutes more;
#         FRESH_TIDY=0 leaves it out, and the summary says so).
#   cross: scripts/cross_check.sh arm64, armhf and s390x, one after the other in one new root
#         (the cross toolchains and the targets' packages installed by the script itself);
#         passes when each printed "gtests: N passed, 0 failed" and "simulation digests: K/K
#         equal to amd64" and exited 0 (about an hour on 2 cores; not part of "both").
# Usage: scripts/fresh_check.sh [demo|test|both|cross] [bookworm|trixie|bullseye] (defaults: both,
# bookworm). bullseye (Debian 11: ros_comm 1.15.9, Noetic's) stands for Ubuntu 20.04 + Noetic,
# whose archive is out of reach here: it builds with CXX=g++-9 (9.3.0, focal's compiler). Needs
# root (or sudo). Logs and the summary go to $FRESH_OUT (default /tmp/modbus_rtu_fresh). Only
# committed work is checked.
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO=$(cd "$(dirname "$0")/.." && pwd)
WHAT=${1:-both}
OUT=${FRESH_OUT:-/tmp/modbus_rtu_fresh}
SUITE=${2:-bookworm}
case $SUITE in
  bookworm | trixie) COMPILER="" ;;
  bullseye) COMPILER="CC=gcc-9 CXX=g++-9" ;;
  *) echo "fresh_check.sh: release '$SUITE' is not bookworm, trixie or bullseye" >&2; exit 2 ;;
esac
case $WHAT in
  demo | test | both | cross) ;;
  *) echo "fresh_check.sh: '$WHAT' is not demo, test, both or cross" >&2; exit 2 ;;
esac
MIRROR=${FRESH_MIRROR:-http://deb.debian.org/debian}
SUDO=""
[ "$(id -u)" = 0 ] || SUDO=sudo
mkdir -p "$OUT"

for tool in mmdebstrap git; do
  command -v "$tool" >/dev/null || {
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends mmdebstrap git
  }
done

ROOT=""
cleanup_root() {
  [ -n "$ROOT" ] || return 0
  for m in dev/pts dev sys proc; do $SUDO umount -l "$ROOT/$m" 2>/dev/null || true; done
  $SUDO rm -rf --one-file-system "$ROOT"
  ROOT=""
}
trap cleanup_root EXIT

# A new root with a new clone; prints nothing, sets ROOT.
new_root() {
  cleanup_root
  ROOT=$(mktemp -d /tmp/modbus_rtu_root.XXXXXX)
  local sources=("deb $MIRROR $SUITE main" "deb $MIRROR $SUITE-updates main")
  # bullseye's security updates (LTS) are listed by the mirror reached here but their files are
  # not served (404): its root goes without them.
  [ "$SUITE" = bullseye ] || sources+=("deb ${MIRROR%/debian}/debian-security $SUITE-security main")
  $SUDO mmdebstrap --variant=minbase --quiet "$SUITE" "$ROOT" "${sources[@]}"
  # A bare root has no name resolution for localhost or this host; roslaunch needs both.
  printf '127.0.0.1 localhost\n127.0.1.1 %s\n::1 localhost ip6-localhost\n' "$(hostname)" |
    $SUDO tee "$ROOT/etc/hosts" >/dev/null
  $SUDO cp -L /etc/resolv.conf "$ROOT/etc/resolv.conf"
  for m in proc sys dev dev/pts; do $SUDO mount --bind "/$m" "$ROOT/$m"; done
  $SUDO git clone --quiet --no-local "$REPO" "$ROOT/root/modbus_rtu_driver"
}

# Runs a command in the root as a user's login shell would: root, HOME=/root, Debian's PATH.
# in_root_offline: the same in a network namespace of its own (loopback only), so that the
# root's rosmasters and test ports cannot meet those of anything else running on this machine
# (a chroot shares the host's network); the installs happen before it, with the network.
in_root_offline() {
  $SUDO unshare -n /bin/bash -c 'ip link set lo up && exec chroot "$@"' _ "$ROOT" "${ROOT_ENV[@]}" \
    /bin/bash -c "cd /root/modbus_rtu_driver && $1"
}
in_root() {
  $SUDO chroot "$ROOT" "${ROOT_ENV[@]}" /bin/bash -c "cd /root/modbus_rtu_driver && $1"
}
# shellcheck disable=SC2206
ROOT_ENV=(/usr/bin/env -i HOME=/root TERM=dumb
  PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin $COMPILER)

status=0
summary=()
if [ "$WHAT" = demo ] || [ "$WHAT" = both ]; then
  new_root
  start=$(date +%s)
  { in_root "scripts/build.sh" && in_root_offline "scripts/demo.sh --duration 20"; } >"$OUT/demo.log" 2>&1 || true
  secs=$(($(date +%s) - start))
  # Live telemetry: rostopic echo printed several PDU messages after the demo's own calls.
  n=$(grep -c '^power: ' "$OUT/demo.log" || true)
  if [ "$n" -ge 3 ] && grep -q 'success: True' "$OUT/demo.log"; then
    summary+=("demo: passed ($n telemetry messages, ${secs} s including installs and build)")
  else
    summary+=("demo: FAILED (see $OUT/demo.log)"); status=1
    tail -30 "$OUT/demo.log"
  fi
fi
if [ "$WHAT" = test ] || [ "$WHAT" = both ]; then
  new_root
  start=$(date +%s)
  { in_root "scripts/build.sh" && in_root_offline "scripts/test.sh"; } >"$OUT/test.log" 2>&1 || true
  secs=$(($(date +%s) - start))
  last=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$OUT/test.log" | tail -1 || true)
  if [[ "$last" =~ ^[1-9][0-9]*\ passed,\ 0\ failed ]]; then
    summary+=("test: passed: $last (${secs} s including installs and build)")
  else
    summary+=("test: FAILED: ${last:-no summary line} (see $OUT/test.log)"); status=1
    tail -40 "$OUT/test.log"
  fi
  if [ "${FRESH_TIDY:-1}" = 0 ]; then
    summary+=("tidy: not run (FRESH_TIDY=0)")
  else
    start=$(date +%s)
    in_root_offline "scripts/tidy.sh" >"$OUT/tidy.log" 2>&1 || true
    secs=$(($(date +%s) - start))
    tidy_version=$(in_root "clang-tidy --version" 2>/dev/null | grep -o 'version [0-9.]*' | head -1)
    last=$(grep -E '^clang-tidy: [0-9]+ warnings' "$OUT/tidy.log" | tail -1 || true)
    if [ "$last" = "clang-tidy: 0 warnings" ]; then
      summary+=("tidy: passed: every file, clang-tidy $tidy_version, 0 warnings (${secs} s)")
    else
      summary+=("tidy: FAILED: clang-tidy $tidy_version: ${last:-no summary line} (see $OUT/tidy.log)")
      status=1
      grep -B1 -A3 'warning:' "$OUT/tidy.log" | head -40 || true
    fi
  fi
fi
if [ "$WHAT" = cross ]; then
  new_root
  for arch in arm64 armhf s390x; do
    start=$(date +%s)
    rc=0
    in_root "scripts/cross_check.sh $arch" >"$OUT/cross_$arch.log" 2>&1 || rc=$?
    secs=$(($(date +%s) - start))
    gtests=$(grep -E '^gtests: ' "$OUT/cross_$arch.log" | tail -1 || true)
    digests=$(grep -E '^simulation digests: ' "$OUT/cross_$arch.log" | tail -1 || true)
    if [ "$rc" = 0 ] && [[ "$gtests" =~ ^gtests:\ [1-9][0-9]*\ passed,\ 0\ failed ]] &&
      [[ "$digests" =~ ^simulation\ digests:\ ([0-9]+)/([0-9]+)\ equal ]] &&
      [ "${BASH_REMATCH[1]}" = "${BASH_REMATCH[2]}" ]; then
      summary+=("cross $arch: passed: $gtests; $digests (${secs} s including installs)")
    else
      summary+=("cross $arch: FAILED (exit $rc): ${gtests:-no gtests line}; ${digests:-no digests line} (see $OUT/cross_$arch.log)")
      status=1
      tail -30 "$OUT/cross_$arch.log"
    fi
  done
fi
# What was checked: the release, its compiler, ROS and the libraries that differ most.
versions=$(in_root "dpkg-query -W -f='\${Package} \${Version}\n' ros-core-dev libcli11-dev \
  libmodbus-dev python3-pymodbus clang-format python3 2>/dev/null; \${CXX:-c++} --version | head -1" 2>&1 || true)
summary=("release: $SUITE${COMPILER:+ ($COMPILER)}" "${summary[@]}" "versions: $(echo "$versions" | paste -sd';' -)")
printf '%s\n' "${summary[@]}" | tee "$OUT/summary.txt"
exit $status
