#!/usr/bin/env bash
# The fail-safe's deterministic simulation (docs/simulation.md) for a long time, or one seed.
#   scripts/simulate.sh --minutes 120       seeds from a new start each run, for 2 hours; prints
#                                           steps, seeds and failures as it goes, then a table
#   scripts/simulate.sh --seed 42           seed 42 (with --minutes: seeds 42, 43, ... )
#   scripts/simulate.sh --replay FILE       one regression case, every frame on stderr
# Options: --steps N (per seed, 2000), --known I2,I6 or --known none (all invariants fail the
# run; the default counts the known open defects' invariants, see docs/simulation.md),
# --cases DIR (where a failure's shrunk case is written; default a new /tmp directory).
# One core, no ROS, no pty. Needs the workspace built (scripts/build.sh).
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS=$("$REPO/scripts/workspace.sh")
EXE=$WS/devel/lib/modbus_rtu_driver/failsafe_simulation
[ -x "$EXE" ] || { echo "$EXE: not built (run scripts/build.sh)" >&2; exit 2; }

minutes="" seed="" steps=2000 known="" cases="" replay=""
while (($#)); do
  case "$1" in
    --minutes) minutes=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --steps) steps=$2; shift 2 ;;
    --known) known=$2; shift 2 ;;
    --cases) cases=$2; shift 2 ;;
    --replay) replay=$2; shift 2 ;;
    *) echo "usage: $0 [--minutes N] [--seed S] [--steps N] [--known A,B|none] [--cases DIR]" \
         "| --replay FILE" >&2
      exit 2 ;;
  esac
done
[ -z "$replay" ] || exec "$EXE" --replay "$replay" --trace
args=(--steps "$steps")
[ -z "$known" ] || args+=(--known "$known")
if [ -z "$cases" ]; then cases=$(mktemp -d /tmp/simulation.XXXXXX); fi
mkdir -p "$cases"
args+=(--cases "$cases")
if [ -n "$minutes" ] && ! [[ "$minutes" =~ ^[1-9][0-9]*$ ]]; then
  echo "--minutes: '$minutes' is not a whole number of minutes (1 or more)" >&2
  exit 2
fi
if [ -z "$minutes" ]; then
  # One seed (the given one, or 1), every line of it.
  exec "$EXE" --seed "${seed:-1}" --seeds 1 "${args[@]}"
fi
# Seeds from `seed` (or from the clock: each long run explores new ones), for `minutes`.
"$EXE" --seed "${seed:-$(date +%s)}" --seconds "$((minutes * 60))" --quiet "${args[@]}" &&
  status=0 || status=$?
echo "shrunk failures (if any): $cases"
exit "$status"
