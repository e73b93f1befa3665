# Shared environment for the project's scripts: system python first (catkin and roslaunch need
# Debian's /usr/bin/python3, not a pyenv build), the workspace location, and the ROS setup.
# Source it; it never exits the calling shell.
GMM_REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export GMM_REPO
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
export GMM_WS="${GMM_WS:-$GMM_REPO/.ws}"
export GMM_BUILD="$GMM_WS/build"
export GMM_DEVEL="$GMM_WS/devel"
gmm_source_ros() {
  # catkin's generated setup scripts read unset variables; relax nounset around them.
  local had_u=0
  case $- in *u*) had_u=1; set +u ;; esac
  if [ -f "$GMM_DEVEL/setup.bash" ]; then
    # shellcheck disable=SC1091
    source "$GMM_DEVEL/setup.bash"
  fi
  [ "$had_u" = 1 ] && set -u
  return 0
}
# A free TCP port for a ROS master of our own (never the default 11311 another master may hold).
gmm_free_port() {
  /usr/bin/python3 -c "import socket; s=socket.socket(); s.bind(('127.0.0.1', 0)); print(s.getsockname()[1])"
}
