#!/usr/bin/env bash
# The install step's choices, in a stand-in environment (nothing is installed): which ROS 1 the
# scripts build against (choose_ros: a ROS from /opt/ros or an already sourced one is used, and
# Debian's ROS packages are then not installed beside it) and which packages each release gets
# (list_packages: except:/only:/debian-ros). A fake /opt/ros (MODBUS_RTU_OPT_ROS), a fake
# release (MODBUS_RTU_RELEASE), and stand-ins for apt-get, dpkg-query and rosdep that only
# record their arguments. One JUnit case in $1: ros_choice_and_release_lists.
set -uo pipefail
RESULTS=$1
mkdir -p "$RESULTS"
# shellcheck source=common.sh
source "$(dirname "$0")/common.sh"
set +e
FAKE=$(mktemp -d)
trap 'rm -rf "$FAKE"' EXIT
failures=()
expect() {  # what, got, wanted
  if [ "$2" != "$3" ]; then failures+=("$1: got '$2', wanted '$3'"); fi
}
expect_has() {  # what, text, word that must (or with !word must not) be a line of it
  local word=${3#!}
  if [ "${3:0:1}" = '!' ]; then
    grep -qx -- "$word" <<<"$2" && failures+=("$1: has $word")
  else
    grep -qx -- "$word" <<<"$2" || failures+=("$1: lacks $word")
  fi
}

# choose_ros
export MODBUS_RTU_OPT_ROS=$FAKE/opt/ros
mkdir -p "$MODBUS_RTU_OPT_ROS"
unset ROS_DISTRO
expect "no /opt/ros, no ROS_DISTRO" "$(choose_ros)" debian
mkdir -p "$FAKE/opt/ros/noetic" "$FAKE/opt/ros/one"
echo 'export FAKE_ROS_SOURCED=noetic ROS_DISTRO=noetic' >"$FAKE/opt/ros/noetic/setup.bash"
echo 'export FAKE_ROS_SOURCED=one ROS_DISTRO=one' >"$FAKE/opt/ros/one/setup.bash"
expect "/opt/ros/noetic present" "$(choose_ros)" "external $FAKE/opt/ros/noetic/setup.bash"
expect "ROS_DISTRO=one picks its own" "$(ROS_DISTRO=one choose_ros)" "external $FAKE/opt/ros/one/setup.bash"
rm -rf "$FAKE/opt/ros/"*
expect "ROS_DISTRO of a sourced ROS, no /opt/ros" "$(ROS_DISTRO=mysrc choose_ros)" \
  "external (already sourced, ROS_DISTRO=mysrc)"
expect "Debian's own ROS_DISTRO=debian" "$(ROS_DISTRO=debian choose_ros)" debian

# list_packages per release
bullseye=$(list_packages bullseye)
trixie=$(list_packages trixie)
external=$(list_packages bookworm no-debian-ros)
expect_has "bullseye" "$bullseye" '!libcli11-dev'
expect_has "bullseye" "$bullseye" '!libclang-rt-dev'
expect_has "bullseye" "$bullseye" g++-9
expect_has "bullseye" "$bullseye" ros-core-dev
expect_has "trixie" "$trixie" libcli11-dev
expect_has "trixie" "$trixie" libclang-rt-dev
expect_has "trixie" "$trixie" '!g++-9'
expect_has "bookworm with a ROS from elsewhere" "$external" '!ros-core-dev'
expect_has "bookworm with a ROS from elsewhere" "$external" '!python3-rostest'
expect_has "bookworm with a ROS from elsewhere" "$external" libmodbus-dev
expect_has "bookworm with a ROS from elsewhere" "$external" mbpoll
grep -qE -- '-[0-9]+-dev' <<<"$bullseye$trixie" && failures+=("a version-pinned name: $(grep -E -- '-[0-9]+-dev' <<<"$trixie")")

# install_deps with a ROS in the fake /opt/ros: sources it, installs the rest, runs rosdep.
mkdir -p "$FAKE/opt/ros/noetic" "$FAKE/bin"
echo 'export FAKE_ROS_SOURCED=noetic ROS_DISTRO=noetic' >"$FAKE/opt/ros/noetic/setup.bash"
printf '#!/bin/sh\nexit 1\n' >"$FAKE/bin/dpkg-query"  # nothing installed
# apt-get too, should anything reach it: this check never installs.
printf '#!/bin/sh\necho "$*" >>"%s/apt-get.calls"\n' "$FAKE" >"$FAKE/bin/apt-get"
printf '#!/bin/sh\necho "$*" >>"%s/rosdep.calls"\n' "$FAKE" >"$FAKE/bin/rosdep"
chmod +x "$FAKE/bin/"*
apt_install() { printf '%s\n' "$@" >"$FAKE/apt.calls"; }
out=$(PATH=$FAKE/bin:$PATH MODBUS_RTU_RELEASE=focal install_deps && echo "sourced=$FAKE_ROS_SOURCED")
echo "$out"
expect_has "install_deps with /opt/ros/noetic" "$out" "sourced=noetic"
grep -q "using the ROS 1 already installed" <<<"$out" || failures+=("install_deps did not say it uses /opt/ros/noetic")
installed=$(cat "$FAKE/apt.calls" 2>/dev/null)
expect_has "apt-get install beside /opt/ros/noetic" "$installed" '!ros-core-dev'
expect_has "apt-get install beside /opt/ros/noetic" "$installed" '!catkin-lint'
expect_has "apt-get install on focal" "$installed" '!libcli11-dev'
expect_has "apt-get install beside /opt/ros/noetic" "$installed" libmodbus-dev
grep -q -- "install --from-paths .* --ignore-src" "$FAKE/rosdep.calls" 2>/dev/null ||
  failures+=("rosdep install was not run")

if ((${#failures[@]})); then
  printf 'ros choice: %s\n' "${failures[@]}"
  case="ros_choice_and_release_lists=$(printf '%s; ' "${failures[@]}")"
else
  echo "ros choice: all cases as expected"
  case=ros_choice_and_release_lists
fi
/usr/bin/python3 "$REPO/scripts/junit.py" "$RESULTS/ros_choice_and_release_lists.xml" install "$case"
((${#failures[@]} == 0))
