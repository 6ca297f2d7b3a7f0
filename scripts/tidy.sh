#!/usr/bin/env bash
# Runs clang-tidy (checks in .clang-tidy) over every C++ source of the package, the tests
# included, using the catkin workspace's compile commands. Prints the findings and
# "clang-tidy: N warnings"; exit 1 when there are any.
source "$(dirname "$0")/common.sh"
install_deps
build_workspace -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
cd "$REPO"
out=$(find src bench test/unit -name '*.cpp' | sort |
  xargs -P"$(nproc)" -n4 clang-tidy -p "$WS/build" --quiet 2>/dev/null || true)
count=$(grep -c "warning:" <<<"$out" || true)
[ "$count" = 0 ] || echo "$out"
echo "clang-tidy: $count warnings"
[ "$count" = 0 ]
