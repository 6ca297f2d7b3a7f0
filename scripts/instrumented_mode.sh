# shellcheck shell=bash disable=SC2034  # MODE, REPO, WS, BUILD...: for the script that sources this file
# Sourced by the instrumented build's scripts, sanitized_tests.sh and fuzz.sh: their first
# argument, read the same way in both, the paths both use, and the one build both run from
# (test/sanitizers/CMakeLists.txt, clang++, ASan + UBSan: the sanitized unit tests and bus node,
# and the libFuzzer targets, on layer libraries compiled once). Takes the mode off "$@":
#   --build-only   MODE=build: build only, every target of both scripts (test.sh calls this once,
#                  while the rostests run)
#   --prebuilt     MODE=run: run what --build-only built (its failure counts)
#   otherwise      MODE=all: build (that script's targets), then run
# Sets REPO (this checkout), WS (its catkin workspace: scripts/workspace.sh) and BUILD.
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS=$("$REPO/scripts/workspace.sh")
MODE=all
case "${1:-}" in
  --build-only) MODE=build; shift ;;
  --prebuilt) MODE=run; shift ;;
esac
BUILD="$WS/instrumented"
FUZZ_TARGETS=(fuzz_frames fuzz_slave fuzz_share)
# "ok" only after a build of every target that succeeded; a build that fails, or builds only the
# fuzz targets, leaves none, and sanitized_tests.sh then fails rather than test old binaries.
SANITIZERS_STATUS=$BUILD/logs/sanitizers.status

# instrumented_build [TARGET...]: configure, then build TARGETs (every target when none), going on
# past an error so that each target that can be built is. The fuzz targets are deleted first: one
# that does not build is missing, and fuzz.sh fails it. Build log: $BUILD/logs/build.log.
instrumented_build() {
  mkdir -p "$BUILD/logs"
  rm -f "$SANITIZERS_STATUS" "${FUZZ_TARGETS[@]/#/$BUILD/}"
  cmake -S "$REPO/test/sanitizers" -B "$BUILD" -G "Unix Makefiles" -DCMAKE_CXX_COMPILER=clang++ \
    -DMSG_INCLUDE="$WS/devel/include" >"$BUILD/logs/configure.log" 2>&1 || {
    tail -20 "$BUILD/logs/configure.log"; echo "instrumented build: configure failed"
    return 1
  }
  local targets=()
  [ $# = 0 ] || targets=(--target "$@")
  cmake --build "$BUILD" "${targets[@]}" -j"$(nproc)" -- -k >"$BUILD/logs/build.log" 2>&1 || {
    grep -E "error|warning: " "$BUILD/logs/build.log" | head -20 || true
    echo "instrumented build: failed, see $BUILD/logs/build.log"
    return 1
  }
  [ $# != 0 ] || echo ok >"$SANITIZERS_STATUS"
}
