# Source me: puts the project venv and Debian's python first on PATH and overlays the catkin workspace.
_MBZ_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck disable=SC1091
source "$_MBZ_ROOT/catkin_ws/devel/setup.bash"
export PATH="${MBZIRC_VENV:-$_MBZ_ROOT/.venv}/bin:/usr/bin:$PATH"
export ROS_PYTHON_VERSION=3
export PYTHONDONTWRITEBYTECODE=1
: "${ROS_HOSTNAME:=localhost}"; export ROS_HOSTNAME
: "${ROS_MASTER_URI:=http://localhost:11311}"; export ROS_MASTER_URI
unset _MBZ_ROOT
