# Shared by demo.sh and test.sh: install missing Debian packages, build the catkin workspace.
# Debian 12 ships ROS 1 under /usr; catkin and rostest need Debian's python, not a pyenv one.
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# The catkin workspace lives outside the repository (its src/ links back to the repository, and
# a workspace inside it would make rosrun and roslaunch walk in circles). One per checkout.
WS=$("$REPO/scripts/workspace.sh")

# Every Debian package the project needs, one list (package.xml declares the same set).
mapfile -t DEPS < <(sed -e 's/#.*//' -e 's/[[:space:]]*$//' -e '/^$/d' "$REPO/scripts/debian_packages.txt")

install_deps() {
  local missing=()
  for p in "${DEPS[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "installing: ${missing[*]}"
    local sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
}

build_workspace() {
  mkdir -p "$WS/src"
  [ -L "$WS/src/modbus_rtu_driver" ] || ln -sfn "$REPO" "$WS/src/modbus_rtu_driver"
  (cd "$WS" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCATKIN_ENABLE_TESTING=ON -j"$(nproc)" "$@")
  set +u
  # shellcheck disable=SC1091
  source "$WS/devel/setup.bash"
  set -u
}
