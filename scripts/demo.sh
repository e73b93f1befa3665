#!/usr/bin/env bash
# The README's main command: the paper's experiment (section V) end to end on a fresh machine.
#
#   1. installs the Debian packages (scripts/install_deps.sh) and builds only what it needs;
#   2. simulates a small town (600 m), its mapping pass (KITTI scans) and a 60 s Downtown drive
#      and a 60 s Downtown Snowy drive (rosbags), from 200 m along a 1.2 km route;
#   3. builds the Gaussian mixture map from the mapping pass;
#   4. runs the vehicle launch headless on the Downtown bag with `rosbag play`
#      (launch/replay.launch, its own ROS master on a free port), recording its output;
#   5. evaluates: mode A (`evaluate bag`: the same pipeline offline, deterministic) on both
#      drives and mode B (`evaluate recorded`) on the replay's recording;
#   6. draws Fig. 8, 9, 10 and Table I (scripts/plot_evaluation.py) and prints Table I.
#
# Everything goes to $GMM_DEMO_DIR (default .ws/demo); existing outputs of a stage are reused
# when its inputs are unchanged (delete the directory to start over). Knobs (environment):
#   GMM_DEMO_DURATION=60   seconds of each drive
#   GMM_DEMO_SNOWY=1       also the Snowy drive (0: Downtown only)
#   GMM_DEMO_REPLAY=1      run the real replay (0: offline evaluation only)
#   GMM_DEMO_REPLAY_SNOWY=0  also replay the Snowy drive
#   GMM_DEMO_OFFSETS=100   scans registered from random 10 m offsets per drive (Fig. 8)
#   GMM_BUILD_LOCK=FILE    build under `flock FILE` (a build directory shared with others)
# docs/evaluation.md explains the outputs and lists measured results and stage times.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
cd "$GMM_REPO"

DEMO="${GMM_DEMO_DIR:-$GMM_WS/demo}"
DURATION="${GMM_DEMO_DURATION:-60}"
SNOWY="${GMM_DEMO_SNOWY:-1}"
REPLAY="${GMM_DEMO_REPLAY:-1}"
REPLAY_SNOWY="${GMM_DEMO_REPLAY_SNOWY:-0}"
OFFSETS="${GMM_DEMO_OFFSETS:-100}"
TOWN=(--town-size 600 --route-length 1200)
SEGMENT=(--start-offset 200 --duration "$DURATION")

STAGES=()
stage_start=0
begin() {
  stage_name="$1"
  stage_start=$(date +%s.%N)
  echo
  echo "=== [demo] $stage_name"
}
end() {
  local secs
  secs=$(/usr/bin/python3 -c "import sys; print('%.1f' % (float(sys.argv[2]) - float(sys.argv[1])))" \
    "$stage_start" "$(date +%s.%N)")
  STAGES+=("$(printf '%-44s %7s s' "$stage_name" "$secs")")
  echo "=== [demo] $stage_name: ${secs} s"
}
fail() {
  echo "[demo] FAILED: $*" >&2
  exit 1
}

begin "install dependencies"
"$GMM_REPO/scripts/install_deps.sh"
end

begin "build (simulate, build_map, evaluate, nodelets)"
mkdir -p "$GMM_WS"  # the log below is opened before build.sh creates it on a fresh clone
LOCK=()
[ -n "${GMM_BUILD_LOCK:-}" ] && LOCK=(flock "$GMM_BUILD_LOCK")
"${LOCK[@]}" "$GMM_REPO/scripts/build.sh" simulate build_map evaluate gmm_map_server_nodelet \
  gmm_matcher_nodelet gmm_ekf_nodelet >"$GMM_WS/demo_build.log" 2>&1 ||
  { tail -n 40 "$GMM_WS/demo_build.log"; fail "build (log: $GMM_WS/demo_build.log)"; }
end
BIN="$GMM_DEVEL/lib/gmm_localization"
gmm_source_ros
mkdir -p "$DEMO"

# A stage's outputs are reused when its command line is unchanged (stamp file with the command).
fresh() {  # fresh STAMP CMD... : true when STAMP holds exactly CMD
  [ -f "$1" ] && [ "$(cat "$1")" = "${*:2}" ]
}

MAPPING_CMD=("$BIN/simulate" "${TOWN[@]}" --pass mapping --kitti "$DEMO/mapping" --kitti-every 2 --quiet)
begin "simulate the mapping pass (KITTI scans)"
if fresh "$DEMO/mapping.done" "${MAPPING_CMD[@]}"; then
  echo "reusing $DEMO/mapping"
else
  rm -rf "$DEMO/mapping" "$DEMO/mapping.done"
  "${MAPPING_CMD[@]}" || fail "simulate mapping"
  echo "${MAPPING_CMD[*]}" >"$DEMO/mapping.done"
fi
end

MAP_CMD=("$BIN/build_map" --kitti "$DEMO/mapping" --kitti-fields xyzi --output "$DEMO/map" --overwrite)
begin "build the map"
if fresh "$DEMO/map.done" "${MAP_CMD[@]}" && [ "$DEMO/map.done" -nt "$DEMO/mapping.done" ]; then
  echo "reusing $DEMO/map"
else
  rm -f "$DEMO/map.done"
  "${MAP_CMD[@]}" >"$DEMO/build_map.log" 2>&1 || { tail -n 20 "$DEMO/build_map.log"; fail "build_map"; }
  grep -A12 "build_map summary" "$DEMO/build_map.log" || true
  echo "${MAP_CMD[*]}" >"$DEMO/map.done"
fi
end

DATASETS=(downtown)
[ "$SNOWY" = 1 ] && DATASETS+=(snowy)
for ds in "${DATASETS[@]}"; do
  SIM_CMD=("$BIN/simulate" "${TOWN[@]}" --pass "$ds" "${SEGMENT[@]}" --bag "$DEMO/$ds.bag" --quiet)
  begin "simulate the $ds drive (${DURATION} s, rosbag)"
  if fresh "$DEMO/$ds.done" "${SIM_CMD[@]}"; then
    echo "reusing $DEMO/$ds.bag"
  else
    rm -f "$DEMO/$ds.bag" "$DEMO/$ds.done"
    "${SIM_CMD[@]}" || fail "simulate $ds"
    echo "${SIM_CMD[*]}" >"$DEMO/$ds.done"
  fi
  end
done

# The replay's initial pose: the bag's first ground truth moved like a GPS fix would be.
initial_pose_args() {
  /usr/bin/python3 "$GMM_REPO/scripts/initial_pose_args.py" "$1"
}

replay() {  # replay DATASET
  local ds="$1" port args
  port=$(gmm_free_port)
  args=$(initial_pose_args "$DEMO/$ds.bag")
  [ -n "$args" ] || fail "no /ground_truth/odom in $DEMO/$ds.bag"
  rm -f "$DEMO/replay_$ds.bag" "$DEMO/replay_$ds.bag.active"
  echo "roslaunch -p $port gmm_localization replay.launch bag:=$DEMO/$ds.bag map:=$DEMO/map" \
    "record:=$DEMO/replay_$ds.bag use_initial_pose:=true $args"
  # shellcheck disable=SC2086
  ROS_MASTER_URI="http://localhost:$port" ROS_LOG_DIR="$DEMO/ros_logs" \
    timeout --signal=INT --kill-after=20 $((DURATION + 180)) \
    roslaunch -p "$port" --screen gmm_localization replay.launch bag:="$DEMO/$ds.bag" \
    map:="$DEMO/map" record:="$DEMO/replay_$ds.bag" use_initial_pose:=true $args \
    >"$DEMO/replay_$ds.log" 2>&1 || true
  # rosbag record finishes its file when the launch stops it.
  for _ in $(seq 20); do [ -f "$DEMO/replay_$ds.bag" ] && break; sleep 0.5; done
  [ -f "$DEMO/replay_$ds.bag" ] ||
    { tail -n 30 "$DEMO/replay_$ds.log"; fail "the replay recorded nothing (log: $DEMO/replay_$ds.log)"; }
}

REPLAYS=()
if [ "$REPLAY" = 1 ]; then
  REPLAYS=(downtown)
  [ "$REPLAY_SNOWY" = 1 ] && [ "$SNOWY" = 1 ] && REPLAYS+=(snowy)
fi
for ds in "${REPLAYS[@]}"; do
  begin "replay $ds: vehicle launch + rosbag play (real time)"
  replay "$ds"
  end
done

EVAL_DIRS=()
for ds in "${DATASETS[@]}"; do
  begin "evaluate $ds offline (evaluate bag)"
  "$BIN/evaluate" bag --bag "$DEMO/$ds.bag" --map "$DEMO/map" --dataset "$ds" \
    --offset-scans "$OFFSETS" --out "$DEMO/eval_$ds" >"$DEMO/eval_$ds.log" 2>&1 ||
    { tail -n 20 "$DEMO/eval_$ds.log"; fail "evaluate bag $ds"; }
  grep -E "^\| this run|^Fig. 8|^Matching" "$DEMO/eval_$ds.log" || true
  EVAL_DIRS+=("$DEMO/eval_$ds")
  end
done
for ds in "${REPLAYS[@]}"; do
  begin "evaluate the $ds replay (evaluate recorded)"
  "$BIN/evaluate" recorded --bag "$DEMO/replay_$ds.bag" --source-bag "$DEMO/$ds.bag" \
    --dataset "$ds" --out "$DEMO/eval_replay_$ds" >"$DEMO/eval_replay_$ds.log" 2>&1 ||
    { tail -n 20 "$DEMO/eval_replay_$ds.log"; fail "evaluate recorded $ds"; }
  grep -E "^\| this run|^Matching" "$DEMO/eval_replay_$ds.log" || true
  EVAL_DIRS+=("$DEMO/eval_replay_$ds")
  end
done

begin "figures and Table I"
/usr/bin/python3 "$GMM_REPO/scripts/plot_evaluation.py" --out "$DEMO/figures" "${EVAL_DIRS[@]}"
end

echo
echo "================ Table I (paper section V) ================"
cat "$DEMO/figures/table1.md"
echo
echo "Figures: $DEMO/figures/fig8_registration.png (Fig. 8), fig9_traversal.png (Fig. 9),"
echo "         fig10_errors.png (Fig. 10); per-run details: $DEMO/eval_*/summary.md"
echo
echo "Stage times (wall):"
printf '  %s\n' "${STAGES[@]}"
