#!/usr/bin/env bash
# roslaunch launch-prefix for the sanitized rostest: runs $SANITIZED_NODE in place of the node
# roslaunch found (its path is our first argument), with the same arguments.
set -euo pipefail
shift
touch "${SANITIZED_NODE}.started"
exec "$SANITIZED_NODE" "$@"
