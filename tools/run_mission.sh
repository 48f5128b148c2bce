#!/usr/bin/env bash
# Runs one simulated Challenge 3 trial (c3_sim.launch) headless and shows its progress in the terminal:
#   tools/run_mission.sh SEED=1 UAVS=3 RTF=4 RECORD=0 SUMMARY=path/summary.json [OUT=dir] [UGV=true]
#                        [RECORD_SLAM=0|1]   (slam.bag: the robots' scans, SLAM and GNSS, for indoor_localization offline)
#                        [GCS=1] [GCS_PORT=8088]   (GCS=0: no web ground station)
#                        [UNCERTAINTY=ideal|realistic]   (the trial's uncertainty, ual_sim README)
#                        [GNSS_DENIED_INDOORS=|0|1]   (no GNSS inside buildings, ual_sim README "No GNSS indoors";
#                         empty: as the uncertainty profile says: realistic denies it, ideal does not)
#                        [INDOOR_SLAM=|0|1]   (hector_mapping + indoor_pose per indoor robot, mbzirc_launchers README;
#                         empty: on wherever GNSS is denied indoors: the agents then fly there on the SLAM pose,
#                         mbzirc_agents README "Pose source")
#                        [WORLD=path.yaml]   (a ual_sim world; default: ual_sim's C3 world)
#                        [INDOOR_SEARCH=explore|plan]   (mbzirc_launchers README, c3_sim.launch arg indoor_search)
# Ends after 20 simulated minutes or when every fire is out; writes summary.json, report.png (and
# mission.bag with RECORD=1) into results/mission_<time>_seed<SEED>/ (or OUT=dir). Uses a free ROS master
# port so it never clashes with another roscore on this machine.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SEED=1; UAVS=3; RTF=4; RECORD=0; RECORD_SLAM=0; SUMMARY=""; OUT=""; UGV=true; DURATION=1200; QUIET=0; GCS=1; GCS_PORT=8088; UNCERTAINTY=ideal
INDOOR_SLAM=""; GNSS_DENIED_INDOORS=""; WORLD=""; INDOOR_SEARCH=explore
SMACH_DEBUG="${SMACH_DEBUG:-0}"  # 1: the agents accept container_init and the viewer's debugger (make mission SMACH_DEBUG=1)
for kv in "$@"; do
  case "$kv" in
    SEED=*|UAVS=*|RTF=*|RECORD=*|RECORD_SLAM=*|SUMMARY=*|OUT=*|UGV=*|DURATION=*|QUIET=*|SMACH_DEBUG=*|GCS=*|GCS_PORT=*|UNCERTAINTY=*|INDOOR_SLAM=*|GNSS_DENIED_INDOORS=*|WORLD=*|INDOOR_SEARCH=*) declare "$kv" ;;
    *) echo "run_mission.sh: unknown argument '$kv'" >&2; exit 2 ;;
  esac
done
[[ "$SEED" =~ ^[0-9]+$ && "$UAVS" =~ ^[0-3]$ && "$RTF" =~ ^[0-9]+([.][0-9]+)?$ ]] \
  || { echo "run_mission.sh: SEED must be an integer, UAVS 0..3, RTF a number" >&2; exit 2; }
[[ "$UNCERTAINTY" =~ ^(ideal|realistic)$ ]] \
  || { echo "run_mission.sh: UNCERTAINTY must be ideal or realistic, got '$UNCERTAINTY'" >&2; exit 2; }
[[ "$INDOOR_SEARCH" =~ ^(plan|explore)$ ]] \
  || { echo "run_mission.sh: INDOOR_SEARCH must be plan or explore, got '$INDOOR_SEARCH'" >&2; exit 2; }
[ -z "$WORLD" ] || [ -f "$WORLD" ] || { echo "run_mission.sh: WORLD: no such file '$WORLD'" >&2; exit 2; }
[ -z "$WORLD" ] || WORLD="$(realpath "$WORLD")"
[[ "$GNSS_DENIED_INDOORS" =~ ^(|0|1)$ && "$INDOOR_SLAM" =~ ^(|0|1)$ ]] \
  || { echo "run_mission.sh: GNSS_DENIED_INDOORS and INDOOR_SLAM must be 0 or 1 (or empty)" >&2; exit 2; }
denied=""; [ "$GNSS_DENIED_INDOORS" = 1 ] && denied=true; [ "$GNSS_DENIED_INDOORS" = 0 ] && denied=false
slam=""; [ "$INDOOR_SLAM" = 1 ] && slam=true; [ "$INDOOR_SLAM" = 0 ] && slam=false
# without GNSS indoors the agents need the SLAM pose there (else they stop at the window: no trusted pose)
[ "$INDOOR_SLAM" = 0 ] && { [ "$denied" = true ] || { [ -z "$denied" ] && [ "$UNCERTAINTY" != ideal ]; }; } \
  && echo "run_mission.sh: warning: GNSS denied indoors with INDOOR_SLAM=0: robots entering a building will hold there (no trusted pose)" >&2
record=false; [ "$RECORD" = 1 ] || [ "$RECORD" = true ] && record=true
record_slam=false; [ "$RECORD_SLAM" = 1 ] || [ "$RECORD_SLAM" = true ] && record_slam=true
smach_debug=false; [ "$SMACH_DEBUG" = 1 ] || [ "$SMACH_DEBUG" = true ] && smach_debug=true
# shellcheck disable=SC1091
set +u; source "$ROOT/env.sh"; set -u
[ -n "$OUT" ] || OUT="$ROOT/results/mission_$(date +%Y%m%d_%H%M%S)_seed${SEED}"
OUT="$(realpath -m "$OUT")"
[ -n "$SUMMARY" ] && SUMMARY="$(realpath -m "$SUMMARY")"
mkdir -p "$OUT"
PORT="$(python -c 'import socket; s=socket.socket(); s.bind(("localhost", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://localhost:$PORT" ROS_HOSTNAME=localhost
export ROS_LOG_DIR="$OUT/ros_logs"
LOG="$OUT/launch.log"
echo "mission: seed $SEED, $UAVS UAVs, UGV $UGV, rtf $RTF, uncertainty $UNCERTAINTY, indoor SLAM ${slam:-where GNSS is denied}, GNSS denied indoors ${denied:-as the profile}, indoor search $INDOOR_SEARCH, world ${WORLD:-default}, record $record -> $OUT (master port $PORT)"

setsid roslaunch -p "$PORT" mbzirc_launchers c3_sim.launch uavs:="$UAVS" ugv:="$UGV" seed:="$SEED" \
  rtf:="$RTF" headless:=true record:="$record" record_slam:="$record_slam" output_dir:="$OUT" summary_path:="$SUMMARY" \
  duration:="$DURATION" smach_debug:="$smach_debug" uncertainty:="$UNCERTAINTY" \
  indoor_slam:="$slam" gnss_denied_indoors:="$denied" \
  world:="$WORLD" indoor_search:="$INDOOR_SEARCH" > "$LOG" 2>&1 &
LAUNCH_PID=$!
GCS_PID=""
if [ "$GCS" != 0 ]; then   # the web ground station, beside the trial (its own launch: it never ends the trial)
  setsid roslaunch --wait mbzirc_launchers ground_station.launch port:="$GCS_PORT" > "$OUT/ground_station.log" 2>&1 &
  GCS_PID=$!
fi
gcs_shown=0
# Ctrl+C to a roslaunch (its own session: setsid), then TERM to its whole group after $2 half-seconds, then
# KILL 5 s later. Why the KILL: a ground station's roslaunch outlived a benchmark's trial (its master gone, INT
# and TERM not acted on), still holding its port and CPU when the next trial started.
running() { ps -o stat= -p "$1" 2>/dev/null | grep -qv '^Z'; }   # not gone, nor a zombie child not yet waited for
stop_group() {
  local pid="$1" tries="$2"
  kill -INT "$pid" 2>/dev/null
  for _ in $(seq 1 "$tries"); do running "$pid" || return 0; sleep 0.5; done
  kill -TERM -- "-$pid" 2>/dev/null
  for _ in $(seq 1 10); do running "$pid" || return 0; sleep 0.5; done
  echo "mission: process group $pid did not stop on INT and TERM: killed" >&2
  kill -KILL -- "-$pid" 2>/dev/null
}
stop_gcs() {   # also a `roslaunch --wait` whose master never came
  [ -n "$GCS_PID" ] || return 0
  stop_group "$GCS_PID" 20
  wait "$GCS_PID" 2>/dev/null; GCS_PID=""
}
stop() {
  stop_gcs
  running "$LAUNCH_PID" && stop_group "$LAUNCH_PID" 30
}
trap 'echo; echo "mission: interrupted"; stop; exit 130' INT TERM

# Wall-time guard: twice the expected time plus start-up.
LIMIT=$(python -c "print(int(2 * $DURATION / max(0.1, $RTF) + 180))")
start=$(date +%s)
shown=0
while kill -0 "$LAUNCH_PID" 2>/dev/null; do
  sleep 1
  if [ -n "$GCS_PID" ] && [ "$gcs_shown" = 0 ]; then
    gport="$(rosparam get /ground_station/bound_port 2>/dev/null)"
    [ -n "$gport" ] && { echo "mission: ground station on http://127.0.0.1:$gport/"; gcs_shown=1; }
  fi
  if [ "$QUIET" != 1 ]; then
    n=$(grep -c '^\[mission\]' "$LOG" 2>/dev/null || true)
    if [ "${n:-0}" -gt "$shown" ]; then grep '^\[mission\]' "$LOG" | tail -n +$((shown + 1)); shown=$n; fi
  fi
  if [ $(( $(date +%s) - start )) -gt "$LIMIT" ]; then
    echo "mission: wall-time limit ${LIMIT}s reached, stopping"; stop; break
  fi
done
wait "$LAUNCH_PID" 2>/dev/null
stop_gcs
[ "$QUIET" != 1 ] && grep '^\[mission\]' "$LOG" | tail -n +$((shown + 1))
if [ -f "$OUT/summary.json" ]; then
  echo "mission: results in $OUT (summary.json, report.png$( [ "$record" = true ] && echo ', mission.bag'))"
  [ -n "$SUMMARY" ] && echo "mission: summary also written to $SUMMARY"
  exit 0
fi
echo "mission: no summary.json was written; last lines of $LOG:" >&2
tail -30 "$LOG" >&2
exit 1
