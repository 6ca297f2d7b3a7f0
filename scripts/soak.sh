#!/usr/bin/env bash
# The node under a cycle of faults for N minutes, with a SetBool caller and a Modbus TCP client on
# the share (scripts/soak.py says what it does and checks). The test command runs 2 minutes.
#   scripts/soak.sh --minutes 8 [--period 20] [--timeout 1.0] [--burst 4] [--junit FILE] [--node EXE]
#     [--wire-log FILE] [--param KEY=VALUE ...]
#   --timeout: the client's, for builds before the share's answer bound (default: the bound the
#   node states); --node: another build's node (its libraries beside it), under this simulator;
#   --burst: clients that each read an absent address at once at each fault (0: none).
# Ends non-zero when a share answer came later than the node's stated bound or out of step, or
# the node's RSS, fds or threads grew. Needs the workspace built (scripts/build.sh).
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS=$("$REPO/scripts/workspace.sh")
[ -f "$WS/devel/setup.bash" ] || { echo "$WS: not built (run scripts/build.sh)" >&2; exit 2; }
set +u
# shellcheck disable=SC1091
source "$WS/devel/setup.bash"
set -u
exec /usr/bin/python3 "$REPO/scripts/soak.py" "$@"
