#!/usr/bin/env bash
# The ROS-free code on another architecture (issue 49): builds the layer libraries, their unit
# tests, the device simulator and the fail-safe's deterministic simulation for ARCH with Debian's
# cross g++ (test/cross/CMakeLists.txt), runs the tests under qemu-user, and runs the same seeds
# of the simulation for ARCH and natively (amd64, same CMake): every seed's digest must be equal.
#   cross_check.sh arm64|armhf|s390x
# armhf: char unsigned (as on arm64), long and pointers 32 bits; s390x: big-endian; arm64: fused
# multiply-add. Installs what scripts/cross_packages.txt lists when missing. Not part of the
# default test command (scripts/test.sh). Exit 0 only when every test passed and every digest
# equals amd64's.
# Environment: CROSS_SEEDS (default 20), CROSS_STEPS (steps per seed, default 2000),
# CROSS_JOBS (default: the cores). Compiles and emulated runs are niced (nice -n 10).
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH  # Debian's python3, not a pyenv one
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

ARCH=${1:-}
case $ARCH in
  arm64) QEMU=qemu-aarch64 ;;
  armhf) QEMU=qemu-arm ;;
  s390x) QEMU=qemu-s390x ;;
  *) echo "usage: $0 arm64|armhf|s390x" >&2; exit 2 ;;
esac
SEEDS=${CROSS_SEEDS:-20}
STEPS=${CROSS_STEPS:-2000}
JOBS=${CROSS_JOBS:-$(nproc)}
# Outside the repository, beside the catkin workspace (scripts/workspace.sh): one per checkout.
TOP=$("$REPO/scripts/workspace.sh")/cross
BUILD=$TOP/$ARCH
NATIVE=$TOP/amd64
# The target's -dev packages that do not co-install with the host's, unpacked (see below).
SYSROOT=$TOP/sysroot-$ARCH
mkdir -p "$BUILD/logs" "$NATIVE"
NICE=(nice -n 10)  # the other work on this machine keeps priority

apt_get() {
  local sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  DEBIAN_FRONTEND=noninteractive $sudo apt-get "$@"
}

installed() {  # package (with :ARCH for a foreign one)
  [ "$(dpkg-query -W -f='${Status}' "$1" 2>/dev/null)" = "install ok installed" ]
}

# NAME, NAME-ARCH or NAME:ARCH for each line of scripts/cross_packages.txt, with its kind.
list_packages() {
  local name word
  while read -r name word; do
    case ${word:-} in
      "") echo "host $name" ;;
      toolchain) echo "host $name-$ARCH" ;;
      target) echo "target $name:$ARCH" ;;
      *) echo "scripts/cross_packages.txt: unknown word '$word' after $name" >&2; return 1 ;;
    esac
  done < <(sed -e 's/#.*//' -e 's/[[:space:]]*$//' -e '/^[[:space:]]*$/d' \
    "$REPO/scripts/cross_packages.txt")
}

# A target package installs beside the host's only when apt can install it without removing
# anything. In Debian 12 that fails for libyaml-cpp-dev (not Multi-Arch: same: its ARCH copy
# would replace amd64's, which the catkin build needs) and, whenever a security update reached
# amd64 but not yet ARCH (libmodbus 3.1.6-2.1+deb12u1: not built for s390x), for a Multi-Arch:
# same package too (every architecture's copy must have the same version). Those are unpacked
# (apt-get download, dpkg -x) into $SYSROOT with their own libraries, for this build alone.
coinstalls() {  # package:ARCH
  local out
  out=$(apt_get install --simulate --no-install-recommends "$1" 2>&1) || return 1
  ! grep -q '^Remv ' <<<"$out"
}

unpack() {  # package:ARCH... (and the libraries they depend on) into $SYSROOT
  local p dep names=()
  for p in "$@"; do
    names+=("$p")
    # One level of Depends (the -dev package's own library); the C and C++ runtimes come with
    # the cross toolchain (/usr/TRIPLET/lib), never from here.
    for dep in $(apt-cache show --no-all-versions "$p" | sed -n 's/^Depends: //p' | tr ',' '\n' |
      sed -e 's/|.*//' -e 's/(.*//' -e 's/:any//' -e 's/[[:space:]]//g'); do
      case $dep in libc6 | libstdc++6 | libgcc-s1) continue ;; esac
      installed "$dep:$ARCH" || names+=("$dep:$ARCH")
    done
  done
  # Afresh each time (a few hundred kB): only the candidates of today's package lists.
  rm -rf "$TOP/debs-$ARCH"
  mkdir -p "$TOP/debs-$ARCH"
  # as root, apt's download sandbox user (_apt) may not write there: download as root
  (cd "$TOP/debs-$ARCH" && apt_get -qq -o APT::Sandbox::User=root download "${names[@]}")
  for p in "$TOP/debs-$ARCH"/*.deb; do dpkg -x "$p" "$SYSROOT"; done
  # Their .pc files name /usr: point them at the unpacked copy.
  find "$SYSROOT" -name '*.pc' -exec sed -i "s|^prefix=/usr|prefix=$SYSROOT/usr|" {} +
  echo "unpacked into $SYSROOT (not installed): ${names[*]}"
}

install_deps() {
  local kind p missing=() targets=() apt=() extract=() updated=0
  # (not `dpkg ... | grep -q`: grep's early exit is a SIGPIPE, a failure under pipefail)
  if ! grep -qx "$ARCH" <<<"$(dpkg --print-foreign-architectures)"; then
    echo "dpkg --add-architecture $ARCH"
    if [ "$(id -u)" = 0 ]; then dpkg --add-architecture "$ARCH"; else
      sudo dpkg --add-architecture "$ARCH"; fi
    apt_get update -qq
    updated=1
  fi
  while read -r kind p; do
    installed "$p" && continue
    if [ "$kind" = host ]; then missing+=("$p"); else targets+=("$p"); fi
  done < <(list_packages)
  if ((${#missing[@]} + ${#targets[@]})) && ((!updated)); then apt_get update -qq; fi
  # The host's packages first: whether a target's co-installs is asked beside them (a target
  # installed first could keep the host's from installing: libyaml-cpp-dev is not Multi-Arch).
  if ((${#missing[@]})); then
    echo "installing: ${missing[*]}"
    apt_get install -y -qq --no-install-recommends "${missing[@]}"
  fi
  for p in ${targets[@]+"${targets[@]}"}; do
    if coinstalls "$p"; then apt+=("$p"); else extract+=("$p"); fi
  done
  if ((${#apt[@]})); then
    echo "installing: ${apt[*]}"
    apt_get install -y -qq --no-install-recommends "${apt[@]}"
  fi
  rm -rf "$SYSROOT"
  if ((${#extract[@]})); then unpack "${extract[@]}"; fi
  return 0
}

install_deps

# The qemu-user binaries must exist: they are what runs every target program below.
command -v "$QEMU" >/dev/null || { echo "$QEMU not found (qemu-user)" >&2; exit 1; }

status=0
build() {  # dir, cmake arguments... ; then `--` and the targets (none: all)
  local dir=$1 args=() targets=()
  shift
  while (($#)) && [ "$1" != -- ]; do args+=("$1"); shift; done
  (($#)) && shift
  for t in "$@"; do targets+=(--target "$t"); done
  mkdir -p "$dir/logs"
  "${NICE[@]}" cmake -S "$REPO/test/cross" -B "$dir" ${args[@]+"${args[@]}"} \
    >"$dir/logs/configure.log" 2>&1 &&
    "${NICE[@]}" cmake --build "$dir" -j"$JOBS" ${targets[@]+"${targets[@]}"} \
      >"$dir/logs/build.log" 2>&1
}

t0=$SECONDS
sysroot_arg=()
[ -d "$SYSROOT" ] && sysroot_arg=(-DMODBUS_RTU_CROSS_SYSROOT="$SYSROOT")
if build "$BUILD" -DCMAKE_TOOLCHAIN_FILE="$REPO/test/cross/$ARCH.cmake" \
  ${sysroot_arg[@]+"${sysroot_arg[@]}"}; then
  echo "build ($ARCH): ok in $((SECONDS - t0)) s"
else
  echo "build ($ARCH): FAILED, see $BUILD/logs/configure.log and build.log"
  grep -hE "error|Error" "$BUILD/logs/configure.log" "$BUILD/logs/build.log" | head -20 || true
  exit 1
fi
# Target programs outside ctest run through the build's `emulated` (test/cross/CMakeLists.txt:
# the toolchain file's emulator command, test/cross/toolchain.cmake says why each option).
EMULATED=$BUILD/emulated
# The native build of the same CMake, only what the digests need.
t0=$SECONDS
if build "$NATIVE" -- failsafe_simulation; then
  echo "build (amd64): ok in $((SECONDS - t0)) s"
else
  echo "build (amd64): FAILED, see $NATIVE/logs/"
  exit 1
fi

# Part 1: the unit tests under qemu (ctest runs each through CMAKE_CROSSCOMPILING_EMULATOR). Each
# writes its gtest XML (GTEST_OUTPUT; qemu passes the environment on) for the case counts; one
# that crashes writes none and counts as failed from ctest's list.
t0=$SECONDS
RESULTS=$BUILD/results
rm -rf "$RESULTS"
mkdir -p "$RESULTS"
ctest_status=0
# Timeouts: the emulated tests are several times slower than native ones.
(cd "$BUILD" && GTEST_OUTPUT="xml:$RESULTS/" "${NICE[@]}" ctest -j"$JOBS" --timeout 900 \
  --output-on-failure >"$BUILD/logs/ctest.log" 2>&1) || ctest_status=$?
programs=$(cd "$BUILD" && ctest -N | sed -n 's/^ *Test *#[0-9]*: *//p')
failed_programs=$(sed -n 's/^[[:space:]]*[0-9]* - \(test_[A-Za-z0-9_]*\) .*/\1/p' \
  "$BUILD/logs/ctest.log" |
  sort -u)
# shellcheck disable=SC2086  # the names, one word each
summary=$(/usr/bin/python3 - "$RESULTS" $programs <<'EOF'
# Passed and failed gtest cases over the programs' XML files; a program without one (a crash,
# a timeout) is one failure more.
import sys, os, xml.etree.ElementTree as ET
results, programs = sys.argv[1], sys.argv[2:]
passed = failed = skipped = missing = 0
for name in programs:
    path = os.path.join(results, name + ".xml")
    if not os.path.exists(path):
        missing += 1
        continue
    for case in ET.parse(path).getroot().iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
        elif case.get("result") == "skipped" or case.find("skipped") is not None:
            skipped += 1
        else:
            passed += 1
print(passed, failed + missing, skipped, missing)
EOF
)
read -r passed failed skipped missing <<<"$summary"
line="gtests: $passed passed, $failed failed ($(wc -w <<<"$programs") programs"
((skipped)) && line+=", $skipped skipped"
((missing)) && line+=", $missing without a result"
echo "$line, $((SECONDS - t0)) s)"
if ((failed)) || ((ctest_status)); then
  status=1
  echo "  failed programs: $(tr '\n' ' ' <<<"$failed_programs")(see $BUILD/logs/ctest.log)"
fi

# Part 2: the same seeds on ARCH and natively; each seed line prints its digest ("seed N: ...
# digest X"; the first seed runs twice to show its digest repeats). The frames' bytes and times
# go into the digest, so equal digests mean the same bus traffic, byte for byte.
t0=$SECONDS
sim_args=(--seed 1 --seeds "$SEEDS" --steps "$STEPS")
sim_status=0 native_status=0
"${NICE[@]}" "$EMULATED" "$BUILD/failsafe_simulation" "${sim_args[@]}" \
  >"$BUILD/logs/simulation.log" 2>&1 || sim_status=$?
"${NICE[@]}" "$NATIVE/failsafe_simulation" "${sim_args[@]}" \
  >"$NATIVE/logs/simulation.log" 2>&1 || native_status=$?
digests() { sed -n 's/^seed \([0-9]*\):.* digest \([0-9a-f]*\).*/\1 \2/p' "$1"; }
equal=0
while read -r seed digest; do
  other=$(digests "$NATIVE/logs/simulation.log" | awk -v s="$seed" '$1 == s {print $2}')
  if [ "$digest" = "$other" ]; then
    equal=$((equal + 1))
  else
    echo "  seed $seed: $ARCH $digest, amd64 ${other:-none}"
  fi
done < <(digests "$BUILD/logs/simulation.log")
echo "simulation digests: $equal/$SEEDS equal to amd64 ($STEPS steps a seed;" \
  "exit $sim_status on $ARCH, $native_status on amd64; $((SECONDS - t0)) s)"
# A seed that fails an invariant fails the run on either architecture; a difference in the
# digests or in the exit status is the cross defect this check is for.
((equal == SEEDS && sim_status == 0 && native_status == 0)) || status=1
exit $status
