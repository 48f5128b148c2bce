#!/usr/bin/env bash
# Idempotent setup of everything the workspace needs, used by the Makefile, CI and the Dockerfile alike:
#   1. Debian's ROS packages (apt, only the ones missing),
#   2. a venv from /usr/bin/python3 with --system-site-packages and the pinned PyPI packages,
#   3. catkin_make of catkin_ws with /usr/bin/python3.
# Each step leaves a stamp and is skipped when its inputs did not change, so a second run takes seconds.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${MBZIRC_VENV:-$ROOT/.venv}"
STAMPS="$ROOT/.setup-stamps"
mkdir -p "$STAMPS"
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
log() { printf '\033[1;34m[setup]\033[0m %s\n' "$*"; }

# ---- 1. apt ---------------------------------------------------------------------------------------
mapfile -t PKGS < <(grep -v '^\s*#' "$ROOT/setup/apt-packages.txt" | awk 'NF{print $1}')
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
  log "installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# ---- 2. venv --------------------------------------------------------------------------------------
req_hash="$(sha1sum "$ROOT/setup/requirements.txt" | cut -c1-40)"
if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$STAMPS/venv" 2>/dev/null)" != "$req_hash" ]; then
  log "creating venv $VENV"
  [ -x "$VENV/bin/python" ] || /usr/bin/python3 -m venv --system-site-packages "$VENV"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r "$ROOT/setup/requirements.txt"
  echo "$req_hash" > "$STAMPS/venv"
fi

# ---- 3. catkin_make -------------------------------------------------------------------------------
# One build at a time: several shells (or CI jobs) may call make at once.
exec 9>"$STAMPS/catkin.lock"; flock 9
# Rebuild only when a build input (package.xml, CMakeLists, msg/srv/action, setup.py) changed.
src_hash="$(cd "$ROOT/catkin_ws/src" && find . \( -name package.xml -o -name CMakeLists.txt -o -name '*.msg' \
  -o -name '*.srv' -o -name '*.action' -o -name setup.py \) -not -path '*/node_modules/*' -print0 | sort -z \
  | xargs -0 sha1sum | sha1sum | cut -c1-40)"
if [ ! -f "$ROOT/catkin_ws/devel/setup.bash" ] || [ "$(cat "$STAMPS/catkin" 2>/dev/null)" != "$src_hash" ]; then
  log "catkin_make (this takes a minute the first time)"
  # Debian's catkin and pluginlib pick 'python3' from PATH: make it the system one for the build.
  ( cd "$ROOT/catkin_ws" && PATH="/usr/bin:$PATH" catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 \
      -DCMAKE_BUILD_TYPE=Release -DCATKIN_ENABLE_TESTING=OFF > "$STAMPS/catkin_make.log" 2>&1 ) || {
    tail -40 "$STAMPS/catkin_make.log"; echo "catkin_make failed, full log: $STAMPS/catkin_make.log" >&2; exit 1; }
  echo "$src_hash" > "$STAMPS/catkin"
fi
log "ready (source env.sh to use the workspace in a shell)"
