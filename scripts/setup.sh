#!/usr/bin/env bash
# Installs the Debian packages vitamin_e needs, only those that are missing.
# Idempotent; needs root (or sudo) only when something is missing.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"

PACKAGES=(
  build-essential cmake catkin libroscpp-dev libnodelet-dev libnodeletlib-dev libnodeletlib-tools
  pluginlib-dev libimage-transport-dev libcv-bridge-dev libtf2-ros-dev libtf2-eigen-dev
  libsensor-msgs-dev libgeometry-msgs-dev libnav-msgs-dev libvisualization-msgs-dev libstd-srvs-dev
  libpcl-conversions-dev libpcl-ros-dev libpcl-dev libopencv-dev libeigen3-dev libyaml-cpp-dev libceres-dev libdeflate-dev
  librosbag-dev python3-rosbag python3-roslaunch python3-rostest librostest-dev rosbash rospack-tools
  rviz libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure libgtest-dev googletest
  python3-rostopic python3-rosnode python3-rosmsg python3-rosservice
  libdiagnostic-updater-dev libdiagnostic-msgs-dev python3-diagnostic-msgs
  python3-sensor-msgs python3-geometry-msgs python3-tf2-msgs python3-std-srvs
  python3-nav-msgs python3-visualization-msgs tf2-tools tf-tools
  ros-std-msgs ros-geometry-msgs ros-sensor-msgs ros-nav-msgs ros-visualization-msgs ros-std-srvs
  python3-numpy python3-yaml python3-matplotlib python3-opencv
  xvfb xauth x11-apps imagemagick
  clang-format clang-tidy-22 ccache
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
ve_info "installing ${#missing[@]} missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || ve_die "need root or sudo to install: ${missing[*]}"
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
ve_info "packages installed"
