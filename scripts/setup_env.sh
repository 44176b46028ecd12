# Shared by scripts/test and scripts/demo: installs what the package needs on a fresh Debian
# bookworm machine (only what is missing) and builds into build/ with a catkin devel space.
# Source it; it defines ensure_deps and build_package.

export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH   # Debian's python3 has the ROS modules
export DEBIAN_FRONTEND=noninteractive
LADAR_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
LADAR_BUILD=${LADAR_BUILD:-$LADAR_ROOT/build}

LADAR_DEB_PACKAGES=(
  build-essential cmake catkin libroscpp-dev libnodeletlib-dev libnodelet-dev libnodeletlib-tools
  libtf2-ros-dev libtf2-eigen-dev libtf2-sensor-msgs-dev libtf2-geometry-msgs-dev tf2-tools
  libpcl-ros-dev libpcl-dev libeigen3-dev libmessage-filters-dev ros-message-generation
  ros-message-runtime ros-std-srvs ros-sensor-msgs ros-geometry-msgs ros-visualization-msgs
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libdiagnostic-updater-dev librosbag-dev python3-rosbag python3-rostest python3-roslaunch
  ros-core-dev rosbash rosout python3-rostopic python3-rosnode python3-rosservice
  python3-rosparam python3-yaml python3-numpy libgtest-dev libbenchmark-dev libyaml-cpp-dev
  libpng-dev valgrind rviz pybind11-dev python3-pytest ${LADAR_EXTRA_PACKAGES:-})

ensure_deps() {
  local missing=()
  local p
  for p in "${LADAR_DEB_PACKAGES[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "Installing ${#missing[@]} Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -q || return 1
  $sudo apt-get install -y -q --no-install-recommends "${missing[@]}" || return 1
}

build_package() {
  local jobs
  jobs=$(nproc 2>/dev/null || echo 2)
  if [ ! -f "$LADAR_BUILD/Makefile" ]; then
    cmake -S "$LADAR_ROOT" -B "$LADAR_BUILD" -DPYTHON_EXECUTABLE=/usr/bin/python3 \
      -DCMAKE_BUILD_TYPE=Release -DCATKIN_ENABLE_TESTING=ON "$@" || return 1
  fi
  make -C "$LADAR_BUILD" -j"$jobs" all || return 1
}
