# shellcheck shell=bash disable=SC2034  # MODE, REPO, WS: for the script that sources this file
# Sourced by the instrumented builds' scripts, sanitized_tests.sh and fuzz.sh: their first
# argument, read the same way in both, and the paths both use. Takes the mode off "$@":
#   --build-only   MODE=build: build only (test.sh builds while the rostests run)
#   --prebuilt     MODE=run: run what --build-only built (its failure counts)
#   otherwise      MODE=all: build, then run
# Sets REPO (this checkout) and WS (its catkin workspace: scripts/workspace.sh).
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS=$("$REPO/scripts/workspace.sh")
MODE=all
case "${1:-}" in
  --build-only) MODE=build; shift ;;
  --prebuilt) MODE=run; shift ;;
esac
