#!/usr/bin/env bash
# Runs clang-tidy (checks in .clang-tidy) over every C++ source of the package, the tests
# included, using the catkin workspace's compile commands. Prints the findings and
# "clang-tidy: N warnings"; exit 1 when there are any.
#   scripts/tidy.sh                     every file (about 25 minutes on 2 cores;
#     scripts/fresh_check.sh runs it once in each release's root, with that release's clang-tidy)
#   scripts/tidy.sh --ros-free RESULTS  the test command's pass: every .cpp of the ROS-free
#     layers (src/core, src/devices, src/failsafe, src/runtime: the frames, the words and bytes of
#     each device, the link, the share's parsing of a client's bytes, the fail-safe's policy),
#     one JUnit case per file in RESULTS. A fixed set, so a run's verdict depends on the code, not
#     on which files the latest commits touched (issue 49). It is the half of the code where a
#     defect costs most and that parses fastest (no ROS headers): about 250 s of CPU here, which
#     the test command's lane beside the tests has; the whole pass (50 min of CPU, the analyzer
#     most of it) does not fit.
source "$(dirname "$0")/common.sh"
ROS_FREE=(src/core src/devices src/failsafe src/runtime)
if [ "${1:-}" = --ros-free ]; then
  results=$2
  mkdir -p "$results"
  rm -f "$results"/*.txt
  cd "$REPO"
  mapfile -t files < <(find "${ROS_FREE[@]}" -name '*.cpp' | sort)
  [ ${#files[@]} -gt 20 ] || { echo "tidy: only ${#files[@]} files in ${ROS_FREE[*]}" >&2; exit 2; }
  # Two at a time: each clang-tidy is one process on one core. A clang-tidy that could not check
  # the file (no compile command, a parse error, none installed) fails its case too.
  printf '%s\n' "${files[@]}" | xargs -P2 -I{} sh -c '
    all=$(clang-tidy -p "$1/build" --quiet "$2" 2>&1); rc=$?
    out=$(printf "%s\n" "$all" | grep -A3 "warning:")
    [ -n "$out" ] || [ $rc = 0 ] || out="clang-tidy exited $rc: $(printf "%s\n" "$all" | tail -n 3)"
    [ -z "$out" ] || printf "%s\n" "$out" >"$3/$(basename "$2").txt"' _ "$WS" {} "$results"
  cases=()
  for f in "${files[@]}"; do
    found=$results/$(basename "$f").txt
    if [ -s "$found" ]; then
      cases+=("$f=@$found")
      echo "clang-tidy: $f:"
      cat "$found"
    else
      cases+=("$f")
    fi
  done
  exec /usr/bin/python3 "$REPO/scripts/junit.py" "$results/tidy.xml" tidy "${cases[@]}"
fi
install_deps
build_workspace -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
cd "$REPO"
out=$(find src bench test/unit -name '*.cpp' | sort |
  xargs -P"$(nproc)" -n4 clang-tidy -p "$WS/build" --quiet 2>/dev/null || true)
# An error (a file clang-tidy could not parse) counts as a finding too.
count=$(grep -cE "(warning|error):" <<<"$out" || true)
[ "$count" = 0 ] || echo "$out"
echo "clang-tidy: $count warnings"
[ "$count" = 0 ]
