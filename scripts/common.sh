# Shared by demo.sh and test.sh: install missing Debian packages, build the catkin workspace.
# Debian and Ubuntu ship ROS 1 under /usr; catkin and rostest need the system's python, not a
# pyenv one. A ROS installed from elsewhere (/opt/ros) is used instead when present (choose_ros).
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# The catkin workspace lives outside the repository (its src/ links back to the repository, and
# a workspace inside it would make rosrun and roslaunch walk in circles). One per checkout.
WS=$("$REPO/scripts/workspace.sh")

# This machine's release (codename), as scripts/debian_packages.txt's except:/only: words name it.
# MODBUS_RTU_RELEASE overrides it (tests of the choice below).
release_codename() {
  if [ -n "${MODBUS_RTU_RELEASE:-}" ]; then echo "$MODBUS_RTU_RELEASE"; return; fi
  (. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-unknown}") || echo unknown
}

# The packages of scripts/debian_packages.txt for release $1; with $2 = no-debian-ros, without
# Debian's ROS packages. One name a line.
list_packages() {
  local release=$1 skip_ros=${2:-} name words w keep
  while read -r name words; do
    keep=1
    for w in $words; do
      case $w in
        except:*) [[ ",${w#except:}," == *",$release,"* ]] && keep=0 ;;
        only:*) [[ ",${w#only:}," == *",$release,"* ]] || keep=0 ;;
        debian-ros) [ "$skip_ros" = no-debian-ros ] && keep=0 ;;
        *) echo "scripts/debian_packages.txt: unknown word '$w' after $name" >&2; return 1 ;;
      esac
    done
    ((keep)) && echo "$name"
  done < <(sed -e 's/#.*//' -e 's/[[:space:]]*$//' -e '/^[[:space:]]*$/d' "$REPO/scripts/debian_packages.txt")
  return 0
}

# Which ROS 1 to build against. Prints one line: "external <setup.bash>" when a ROS is already
# installed from elsewhere (ROS_DISTRO set with its /opt/ros/<distro>/setup.bash, or any
# /opt/ros/*/setup.bash; Noetic from packages.ros.org, ROS-O, a source install), else "debian"
# (Debian's or Ubuntu's own ROS 1 packages under /usr, installed by install_deps). Installing
# Debian's ROS beside another ROS would give two roscpp, two catkin and mixed message packages.
# MODBUS_RTU_OPT_ROS stands for /opt/ros (tests of this choice).
choose_ros() {
  local opt=${MODBUS_RTU_OPT_ROS:-/opt/ros} setup
  if [ -n "${ROS_DISTRO:-}" ] && [ -f "$opt/$ROS_DISTRO/setup.bash" ]; then
    echo "external $opt/$ROS_DISTRO/setup.bash"; return
  fi
  for setup in "$opt"/*/setup.bash; do
    [ -f "$setup" ] && { echo "external $setup"; return; }
  done
  # ROS_DISTRO without /opt/ros/ROS_DISTRO: a ROS whose environment is already sourced (a source
  # install, a workspace overlay). Debian's own ROS names itself "debian" there.
  if [ -n "${ROS_DISTRO:-}" ] && [ "$ROS_DISTRO" != debian ]; then
    echo "external (already sourced, ROS_DISTRO=$ROS_DISTRO)"; return
  fi
  echo debian
}

apt_install() {
  local sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "$@"
}

install_deps() {
  local release choice skip="" missing=() p
  release=$(release_codename)
  choice=$(choose_ros)
  if [[ $choice == external* ]]; then
    skip=no-debian-ros
    local setup=${choice#external }
    if [ -f "$setup" ]; then
      set +u
      # shellcheck disable=SC1090
      source "$setup"
      set -u
    fi
    echo "ROS: using the ROS 1 already installed ($setup, ROS_DISTRO=${ROS_DISTRO:-?});" \
      "not installing Debian's ROS packages beside it"
  fi
  local deps
  deps=$(list_packages "$release" $skip) || return 1
  mapfile -t DEPS <<<"$deps"
  for p in "${DEPS[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "installing ($release): ${missing[*]}"
    apt_install "${missing[@]}"
  fi
  if [ -n "$skip" ]; then
    if command -v rosdep >/dev/null; then
      echo "ROS: rosdep install --from-paths $REPO --ignore-src -y -r (the ROS packages of package.xml for $ROS_DISTRO)"
      rosdep install --from-paths "$REPO" --ignore-src -y -r || echo "ROS: rosdep could not install everything (see above)"
    else
      echo "ROS: no rosdep here; the ROS packages package.xml names (roscpp, diagnostic_updater," \
        "topic_tools, rosbag, rostest, ...) must come with the ROS at ${ROS_DISTRO:-/opt/ros}"
    fi
  fi
}

build_workspace() {
  mkdir -p "$WS/src"
  [ -L "$WS/src/modbus_rtu_driver" ] || ln -sfn "$REPO" "$WS/src/modbus_rtu_driver"
  (cd "$WS" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
    -DCATKIN_ENABLE_TESTING=ON -j"$(nproc)" "$@")
  set +u
  # shellcheck disable=SC1091
  source "$WS/devel/setup.bash"
  set -u
}
