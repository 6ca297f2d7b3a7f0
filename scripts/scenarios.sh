#!/usr/bin/env bash
# Randomized fail-safe scenarios (issue 24, test/scenarios/) on the real node and the simulator,
# longer than the test command's 60 s, or one seed again.
#   scripts/scenarios.sh --minutes 30      runs seeds for 30 minutes (5-minute runs, a new seed
#                                          each), then prints steps run, failures and their seeds
#   scripts/scenarios.sh --seed N          replays seed N (stops at its first failure)
# Options: --strict (check the known defects of test/scenarios/known_defects.txt too),
#   --known A,B (only these known defects relaxed, instead of the file's list),
#   --shrink (shrink a failure to its shortest sequence: slow), --steps N (per example, 12).
# Runs in its own network namespace (rostest's master port, the share's port picked at run time).
# Needs the workspace built (scripts/build.sh).
set -euo pipefail
if [ -z "${SCENARIOS_IN_NETNS:-}" ]; then
  exec unshare -n env SCENARIOS_IN_NETNS=1 bash -c 'ip link set lo up; exec "$0" "$@"' "$0" "$@"
fi
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS=$("$REPO/scripts/workspace.sh")
set +u
# shellcheck disable=SC1091
source "$WS/devel/setup.bash"
set -u

minutes=0 seed=0 known="" shrink=false steps=12
while (($#)); do
  case "$1" in
    --minutes) minutes=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --strict) known=none; shift ;;
    --known) known=$2; shift 2 ;;
    --shrink) shrink=true; shift ;;
    --steps) steps=$2; shift 2 ;;
    *) echo "usage: $0 [--minutes N | --seed N] [--strict | --known A,B] [--shrink] [--steps N]" >&2
      exit 2 ;;
  esac
done

LOGDIR=$(mktemp -d /tmp/scenarios.XXXXXX)
run() {  # run SEED SECONDS -> the run's output in $LOGDIR/SEED.log, summary line on stdout
  local s=$1 secs=$2 limit=$(($2 + 600))
  [ "$shrink" = true ] && limit=$((limit + 3600))
  SCENARIOS_LOG="$LOGDIR/$s.log" rostest modbus_rtu_driver scenarios.test seed:="$s" \
    seconds:="$secs" steps:="$steps" shrink:="$shrink" known_defects:="$known" \
    time_limit:="$limit" dir:="$LOGDIR/run$s" >"$LOGDIR/$s.rostest.log" 2>&1 || true
  grep -E '^SCENARIOS seed [0-9]+:' "$LOGDIR/$s.log" 2>/dev/null ||
    echo "SCENARIOS seed $s: no summary (see $LOGDIR/$s.rostest.log)"
}

if [ "$seed" != 0 ]; then
  run "$seed" 600
  # The last example (on a failure: its replay, with Hypothesis's listing of the steps).
  tac "$LOGDIR/$seed.log" | sed '/\] example [0-9]*:/q' | tac
  echo "log: $LOGDIR/$seed.log"
  exit 0
fi
((minutes > 0)) || minutes=1
end=$(($(date +%s) + minutes * 60))
total_steps=0 failures=0 failed_seeds=()
while (($(date +%s) < end)); do
  left=$((end - $(date +%s)))
  s=$(shuf -i 1-2147483647 -n 1)
  line=$(run "$s" $((left < 300 ? left : 300)))
  echo "$line"
  n=$(sed -nE 's/.* ([0-9]+) steps in .*/\1/p' <<<"$line")
  total_steps=$((total_steps + ${n:-0}))
  if ! grep -q "no invariant failed" <<<"$line"; then
    failures=$((failures + 1))
    failed_seeds+=("$s")
  fi
done
echo "scenarios: $total_steps steps, $failures failed run(s)${failed_seeds[*]:+, seeds: ${failed_seeds[*]}} (logs: $LOGDIR)"
((failures == 0))
