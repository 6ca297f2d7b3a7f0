#!/usr/bin/env bash
# Runs clang-tidy (checks in .clang-tidy) over every C++ source of the package, the tests
# included, using the catkin workspace's compile commands. Prints the findings and
# "clang-tidy: N warnings"; exit 1 when there are any.
#   scripts/tidy.sh                       every file (about 25 minutes on 2 cores)
#   scripts/tidy.sh --changed RESULTS     only the .cpp files changed since the merge base with
#     origin/main, or, where there is none (a clean clone of main, as CI has), in the last
#     $TIDY_COMMITS commits (10): the test command's pass, one JUnit case per file in RESULTS
#     (the whole pass does not fit in its time)
source "$(dirname "$0")/common.sh"
if [ "${1:-}" = --changed ]; then
  results=$2
  mkdir -p "$results"
  cd "$REPO"
  base=""
  if git rev-parse -q --verify origin/main >/dev/null; then
    base=$(git merge-base HEAD origin/main)
    [ "$base" = "$(git rev-parse HEAD)" ] && base=""
  fi
  if [ -z "$base" ]; then
    n=$(git rev-list --count HEAD)
    back=$((n - 1 < ${TIDY_COMMITS:-10} ? n - 1 : ${TIDY_COMMITS:-10}))
    base=$(git rev-parse "HEAD~$back")
  fi
  mapfile -t files < <(git diff --name-only "$base" -- 'src/*.cpp' 'bench/*.cpp' 'test/unit/*.cpp' |
    while read -r f; do [ -f "$f" ] && echo "$f"; done | sort)
  cases=()
  for f in "${files[@]}"; do
    out=$(clang-tidy -p "$WS/build" --quiet "$f" 2>/dev/null | grep -A3 "warning:" || true)
    if [ -n "$out" ]; then
      printf '%s\n' "$out" >"$results/$(basename "$f").txt"
      cases+=("$f=@$results/$(basename "$f").txt")
      echo "clang-tidy: $f:"
      echo "$out"
    else
      cases+=("$f")
    fi
  done
  [ ${#cases[@]} -gt 0 ] || cases=("no_cpp_changed_since_${base:0:7}")
  exec /usr/bin/python3 "$REPO/scripts/junit.py" "$results/tidy.xml" tidy "${cases[@]}"
fi
install_deps
build_workspace -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
cd "$REPO"
out=$(find src bench test/unit -name '*.cpp' | sort |
  xargs -P"$(nproc)" -n4 clang-tidy -p "$WS/build" --quiet 2>/dev/null || true)
count=$(grep -c "warning:" <<<"$out" || true)
[ "$count" = 0 ] || echo "$out"
echo "clang-tidy: $count warnings"
[ "$count" = 0 ]
