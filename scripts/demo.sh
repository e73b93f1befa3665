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
#   6. the imperfect world (GMM_DEMO_IMPERFECT=1): the same town mapped from SLAM-like poses by
#      a vehicle with calibration errors (simulate --map-pose-error realistic --extrinsic-error
#      realistic), drives a few months later (--aging realistic: construction sites, containers,
#      grown trees, a repaved road) by a vehicle with its own calibration errors, evaluated
#      offline against the exact truth and against the truth in the map's frame (--map-poses);
#   7. the reflectivity baseline (GMM_DEMO_REFLECTIVITY=1): each map's reflectivity layer
#      (build_map --layer reflectivity) and every drive matched against it (evaluate
#      --method reflectivity), the Levinson row of Table I measured instead of quoted;
#      and (with the Snowy drive) Fig. 2: the snowy drive's own reflectivity layer beside the
#      map's (scripts/plot_reflectivity_map.py); the fused method (GMM_DEMO_FUSED=1: both
#      layers' likelihoods summed, evaluate --method fused) on every drive; and GPS as the paper
#      used it for the baseline (GMM_DEMO_GPS=1: the drives carry simulated GNSS fixes, the maps
#      the simulator's georeference, and the reflectivity method is evaluated once more with
#      evaluate --gps);
#   8. draws Fig. 8, 9, 10 and Table I (scripts/plot_evaluation.py) and prints Table I.
#
# Everything goes to $GMM_DEMO_DIR (default .ws/demo); existing outputs of a stage are reused
# when its inputs are unchanged (delete the directory to start over). Knobs (environment):
#   GMM_DEMO_DURATION=60   seconds of each drive
#   GMM_DEMO_SNOWY=1       also the Snowy drive (0: Downtown only)
#   GMM_DEMO_REPLAY=1      run the real replay (0: offline evaluation only)
#   GMM_DEMO_REPLAY_SNOWY=0  also replay the Snowy drive
#   GMM_DEMO_OFFSETS=100   scans registered from random 10 m offsets per drive (Fig. 8)
#   GMM_DEMO_IMPERFECT=1   also the imperfect world (0: the perfect-map world only)
#   GMM_DEMO_REFLECTIVITY=1  also the reflectivity method (0: the paper's height method only)
#   GMM_DEMO_FUSED=1       also the fused method (height + reflectivity)
#   GMM_DEMO_GPS=1         also the reflectivity method with GPS (needs GMM_DEMO_REFLECTIVITY=1)
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
IMPERFECT="${GMM_DEMO_IMPERFECT:-1}"
REFLECTIVITY="${GMM_DEMO_REFLECTIVITY:-1}"
FUSED="${GMM_DEMO_FUSED:-1}"
GPS="${GMM_DEMO_GPS:-1}"
[ "$REFLECTIVITY" = 1 ] || GPS=0
# Where the simulated world sits on the Earth (simulate's defaults): the maps carry it when the
# drives carry GNSS fixes, so that evaluate --gps can place the fixes in the map.
GEOREFERENCE=(--utm-zone 17N --georef-origin 277000,4686000,250)
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

# The imperfect world's options (docs/simulator.md): the mapping vehicle's poses come from a
# SLAM back end and its sensors are calibrated to within 1-2 cm / 0.1-0.2 deg; the town has aged
# between the mapping pass and the drives, whose vehicle has its own calibration errors.
IMPERFECT_MAPPING=(--map-pose-error realistic --extrinsic-error realistic)
IMPERFECT_DRIVE=(--aging realistic --extrinsic-error realistic)

map_world() {  # map_world SUFFIX MAPPING_OPTIONS... : the mapping pass and its map
  local sfx="$1"
  shift
  local mapping_cmd=("$BIN/simulate" "${TOWN[@]}" --pass mapping --kitti "$DEMO/mapping$sfx"
    --kitti-every 2 --quiet "$@")
  begin "simulate the mapping pass$sfx (KITTI scans)"
  if fresh "$DEMO/mapping$sfx.done" "${mapping_cmd[@]}"; then
    echo "reusing $DEMO/mapping$sfx"
  else
    rm -rf "$DEMO/mapping$sfx" "$DEMO/mapping$sfx.done"
    "${mapping_cmd[@]}" || fail "simulate mapping$sfx"
    echo "${mapping_cmd[*]}" >"$DEMO/mapping$sfx.done"
  fi
  end
  build_layer "$sfx" "" height
  if [ "$REFLECTIVITY" = 1 ] || [ "$FUSED" = 1 ]; then
    build_layer "$sfx" /reflectivity reflectivity
  fi
  return 0
}

build_layer() {  # build_layer SUFFIX SUBDIR LAYER : one layer of the map of a world
  local sfx="$1" sub="$2" layer="$3"
  local out="$DEMO/map$sfx$sub" stamp="$DEMO/map$sfx${sub//\//_}.done"
  local map_cmd=("$BIN/build_map" --kitti "$DEMO/mapping$sfx" --kitti-fields xyzi
    --layer "$layer" --output "$out" --overwrite)
  # The georeference lives in the height map's manifest (the reflectivity layer inside it
  # inherits it).
  [ "$GPS" = 1 ] && [ "$layer" = height ] && map_cmd+=("${GEOREFERENCE[@]}")
  begin "build the $layer map$sfx"
  if fresh "$stamp" "${map_cmd[@]}" && [ "$stamp" -nt "$DEMO/mapping$sfx.done" ]; then
    echo "reusing $out"
  else
    rm -f "$stamp"
    "${map_cmd[@]}" >"$DEMO/build_map$sfx${sub//\//_}.log" 2>&1 ||
      { tail -n 20 "$DEMO/build_map$sfx${sub//\//_}.log"; fail "build_map $layer$sfx"; }
    grep -A14 "build_map summary" "$DEMO/build_map$sfx${sub//\//_}.log" || true
    echo "${map_cmd[*]}" >"$stamp"
  fi
  end
}

drive() {  # drive DATASET SUFFIX DRIVE_OPTIONS... : a localization drive as a rosbag
  local ds="$1" sfx="$2"
  shift 2
  local sim_cmd=("$BIN/simulate" "${TOWN[@]}" --pass "$ds" "${SEGMENT[@]}"
    --bag "$DEMO/$ds$sfx.bag" --quiet "$@")
  [ "$GPS" = 1 ] && sim_cmd+=(--gnss realistic "${GEOREFERENCE[@]}")
  begin "simulate the $ds$sfx drive (${DURATION} s, rosbag)"
  if fresh "$DEMO/$ds$sfx.done" "${sim_cmd[@]}"; then
    echo "reusing $DEMO/$ds$sfx.bag"
  else
    rm -f "$DEMO/$ds$sfx.bag" "$DEMO/$ds$sfx.done"
    "${sim_cmd[@]}" || fail "simulate $ds$sfx"
    echo "${sim_cmd[*]}" >"$DEMO/$ds$sfx.done"
  fi
  end
}

map_world ""
DATASETS=(downtown)
[ "$SNOWY" = 1 ] && DATASETS+=(snowy)
for ds in "${DATASETS[@]}"; do drive "$ds" ""; done
if [ "$IMPERFECT" = 1 ]; then
  map_world _imperfect "${IMPERFECT_MAPPING[@]}"
  for ds in "${DATASETS[@]}"; do drive "$ds" _imperfect "${IMPERFECT_DRIVE[@]}"; done
fi

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
evaluate_offline() {  # evaluate_offline DATASET SUFFIX WORLD METHOD GPS EVALUATE_OPTIONS...
  local ds="$1" sfx="$2" world="$3" method="$4" gps="$5"
  shift 5
  local name="$ds$sfx" offsets="$OFFSETS" what="$method method"
  # The reflectivity method's wide searches prune little (in snow about a third of the
  # exhaustive poses, seconds each), the fused method's carry both layers: a fifth of the
  # Fig. 8 registrations. With GPS: the drive only (the registrations do not use the fixes).
  [ "$method" = height ] || { name="${ds}${sfx}_$method"; offsets=$((OFFSETS / 5)); }
  if [ "$gps" = 1 ]; then
    name="${name}_gps"
    offsets=0
    what="$what with GPS"
    set -- "$@" --gps
  fi
  begin "evaluate $ds offline, $world world, $what (evaluate bag)"
  local rc=0
  "$BIN/evaluate" bag --bag "$DEMO/$ds$sfx.bag" --map "$DEMO/map$sfx" --dataset "$ds" \
    --world "$world" --method "$method" --offset-scans "$offsets" --out "$DEMO/eval_$name" \
    "$@" >"$DEMO/eval_$name.log" 2>&1 || rc=$?
  # 3: the run never localized (no data to score): a result (e.g. reflectivity in snow), which
  # Table I reports as "-" with its match rate; anything else is a failure.
  if [ "$rc" = 3 ]; then
    echo "[demo] $name: no data: $(grep -m1 'no data' "$DEMO/eval_$name.log")"
  elif [ "$rc" != 0 ]; then
    tail -n 20 "$DEMO/eval_$name.log"
    fail "evaluate bag $name"
  fi
  grep -E "^\| this run|^\| the map|^Fig. 8|^Matching" "$DEMO/eval_$name.log" || true
  EVAL_DIRS+=("$DEMO/eval_$name")
  end
}
# Each entry: METHOD:GPS.
RUNS=(height:0)
[ "$REFLECTIVITY" = 1 ] && RUNS+=(reflectivity:0)
[ "$GPS" = 1 ] && RUNS+=(reflectivity:1)
[ "$FUSED" = 1 ] && RUNS+=(fused:0)
for run in "${RUNS[@]}"; do
  method="${run%%:*}"
  gps="${run#*:}"
  for ds in "${DATASETS[@]}"; do evaluate_offline "$ds" "" perfect "$method" "$gps"; done
  if [ "$IMPERFECT" = 1 ]; then
    for ds in "${DATASETS[@]}"; do
      evaluate_offline "$ds" _imperfect imperfect "$method" "$gps" \
        --map-poses "$DEMO/mapping_imperfect"
    done
  fi
done
for ds in "${REPLAYS[@]}"; do
  begin "evaluate the $ds replay (evaluate recorded)"
  "$BIN/evaluate" recorded --bag "$DEMO/replay_$ds.bag" --source-bag "$DEMO/$ds.bag" \
    --dataset "$ds" --world perfect --out "$DEMO/eval_replay_$ds" >"$DEMO/eval_replay_$ds.log" 2>&1 ||
    { tail -n 20 "$DEMO/eval_replay_$ds.log"; fail "evaluate recorded $ds"; }
  grep -E "^\| this run|^Matching" "$DEMO/eval_replay_$ds.log" || true
  EVAL_DIRS+=("$DEMO/eval_replay_$ds")
  end
done

if [ "$REFLECTIVITY" = 1 ] && [ "$SNOWY" = 1 ]; then
  # Fig. 2: the snowy drive's own reflectivity layer (every 2nd scan, placed with the truth) beside
  # the map's, over the 40 m square with the most lane paint in the map.
  begin "Fig. 2: reflectivity layer of the snowy drive"
  fig2_cmd=("$BIN/build_map" --bag "$DEMO/snowy.bag" --every 2 --layer reflectivity
    --output "$DEMO/reflectivity_snowy" --overwrite --quiet)
  if fresh "$DEMO/reflectivity_snowy.done" "${fig2_cmd[@]}" &&
    [ "$DEMO/reflectivity_snowy.done" -nt "$DEMO/snowy.done" ]; then
    echo "reusing $DEMO/reflectivity_snowy"
  else
    rm -f "$DEMO/reflectivity_snowy.done"
    "${fig2_cmd[@]}" >"$DEMO/build_map_reflectivity_snowy.log" 2>&1 ||
      { tail -n 20 "$DEMO/build_map_reflectivity_snowy.log"; fail "build_map reflectivity (snowy drive)"; }
    echo "${fig2_cmd[*]}" >"$DEMO/reflectivity_snowy.done"
  fi
  mkdir -p "$DEMO/figures"
  /usr/bin/python3 "$GMM_REPO/scripts/plot_reflectivity_map.py" "$DEMO/map/reflectivity" \
    "$DEMO/reflectivity_snowy" --center auto --size 40 \
    --labels "clear: the map (mapping pass),snow: the snowy drive" \
    --title "Fig. 2: ground reflectivity, clear and snowy" \
    --out "$DEMO/figures/fig2_reflectivity_clear_snowy.png"
  end
fi

begin "figures and Table I"
/usr/bin/python3 "$GMM_REPO/scripts/plot_evaluation.py" --out "$DEMO/figures" "${EVAL_DIRS[@]}"
end

echo
echo "================ Table I (paper section V) ================"
cat "$DEMO/figures/table1.md"
echo
echo "Figures: $DEMO/figures/fig8_registration.png (Fig. 8), fig9_traversal.png (Fig. 9),"
echo "         fig10_errors.png (Fig. 10), fig10_methods_*.png (Fig. 10 by method),"
echo "         fig2_reflectivity_clear_snowy.png (Fig. 2); per-run details: $DEMO/eval_*/summary.md"
echo
echo "Stage times (wall):"
printf '  %s\n' "${STAGES[@]}"
