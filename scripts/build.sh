#!/usr/bin/env bash
# Installs what is missing and builds the package (and its tests) in .build/ws.
source "$(dirname "$0")/common.sh"
install_deps
build_workspace "$@"
