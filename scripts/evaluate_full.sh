#!/usr/bin/env bash
# The full evaluation of the paper's section V: the 3 km Downtown and Downtown Snowy drives in a
# 1.2 km town (the simulator's defaults), the map from a full mapping pass, the offline
# evaluation of both drives (Table I, Fig. 8 with 300 offset registrations each, Fig. 9, 10,
# obstacles) and, unless GMM_FULL_REPLAY=0, a real-time replay of both with the vehicle launch.
#
# Long: about 7.3 min of driving per drive. On the 2-core machine of docs/evaluation.md:
# simulation ~15 min, map ~5 min, offline evaluation ~15-20 min per drive, replays 8 min each.
# Disk: a full-rate merged bag is ~19 GB per drive (GMM_FULL_AZIMUTH_STEP=0.332 halves it, at the
# cost of a sparser sensor than the paper's). Outputs in $GMM_FULL_DIR (default .ws/full).
#
#   ./scripts/evaluate_full.sh            # everything
#   GMM_FULL_REPLAY=0 ./scripts/evaluate_full.sh   # offline evaluation only
#   GMM_FULL_IMPERFECT=1 ...   # also the imperfect world (SLAM-like map poses, calibration
#                              # errors, an aged town): a second mapping pass, map and two drives
#   GMM_FULL_KEEP_BAGS=0 ...   # delete each drive's bag once scored (the disk holds one at a time)
#   GMM_FULL_OFFSETS=N ...     # Fig. 8 registrations per drive (300; 0: none)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
cd "$GMM_REPO"

OUT="${GMM_FULL_DIR:-$GMM_WS/full}"
REPLAY="${GMM_FULL_REPLAY:-1}"
IMPERFECT="${GMM_FULL_IMPERFECT:-0}"
KEEP_BAGS="${GMM_FULL_KEEP_BAGS:-1}"
OFFSETS="${GMM_FULL_OFFSETS:-300}"
AZ=()
[ -n "${GMM_FULL_AZIMUTH_STEP:-}" ] && AZ=(--azimuth-step "$GMM_FULL_AZIMUTH_STEP")
TOWN=(--town-size 1200 --route-length 3000)

"$GMM_REPO/scripts/install_deps.sh"
mkdir -p "$GMM_WS"  # the log below is opened before build.sh creates it on a fresh clone
"$GMM_REPO/scripts/build.sh" simulate build_map evaluate gmm_map_server_nodelet \
  gmm_matcher_nodelet gmm_ekf_nodelet >"$GMM_WS/full_build.log" 2>&1 ||
  { tail -n 40 "$GMM_WS/full_build.log"; exit 1; }
gmm_source_ros
BIN="$GMM_DEVEL/lib/gmm_localization"
mkdir -p "$OUT"
t() { local s=$SECONDS; "$@"; echo "[full] $(basename "$1") ${*:2:2}: $((SECONDS - s)) s"; }

# The imperfect world (GMM_FULL_IMPERFECT=1; docs/simulator.md, as in demo.sh): the mapping
# vehicle's poses come from a SLAM back end and its sensors carry calibration errors; the town
# has aged before the drives, whose vehicle has calibration errors of its own. Its drives are
# scored against the exact truth and against the truth in the map's frame (--map-poses).
IMPERFECT_MAPPING=(--map-pose-error realistic --extrinsic-error realistic)
IMPERFECT_DRIVE=(--aging realistic --extrinsic-error realistic)

map_world() {  # map_world SUFFIX MAPPING_OPTIONS... : the mapping pass and its map
  local sfx="$1"
  shift
  [ -f "$OUT/mapping$sfx.done" ] || {
    t "$BIN/simulate" "${TOWN[@]}" "${AZ[@]}" --pass mapping --kitti "$OUT/mapping$sfx" \
      --kitti-every 2 --quiet "$@"
    touch "$OUT/mapping$sfx.done"
  }
  [ -f "$OUT/map$sfx.done" ] || {
    t "$BIN/build_map" --kitti "$OUT/mapping$sfx" --kitti-fields xyzi --output "$OUT/map$sfx" \
      --overwrite
    touch "$OUT/map$sfx.done"
  }
}

DIRS=()
run_drive() {  # run_drive DATASET SUFFIX WORLD : simulate, evaluate offline, replay
  local ds="$1" sfx="$2" world="$3" port args
  local bag="$OUT/$ds$sfx.bag" options=()
  [ "$world" = imperfect ] && options=("${IMPERFECT_DRIVE[@]}")
  [ -f "$OUT/$ds$sfx.done" ] || {
    t "$BIN/simulate" "${TOWN[@]}" "${AZ[@]}" --pass "$ds" --bag "$bag" --quiet "${options[@]}"
    touch "$OUT/$ds$sfx.done"
  }
  local scoring=(--world "$world")
  [ "$world" = imperfect ] && scoring+=(--map-poses "$OUT/mapping$sfx")
  t "$BIN/evaluate" bag --bag "$bag" --map "$OUT/map$sfx" --dataset "$ds" "${scoring[@]}" \
    --offset-scans "$OFFSETS" --out "$OUT/eval_$ds$sfx" | tee "$OUT/eval_$ds$sfx.log" |
    grep -E "^\|" || true
  DIRS+=("$OUT/eval_$ds$sfx")
  if [ "$REPLAY" = 1 ]; then
    port=$(gmm_free_port)
    args=$(/usr/bin/python3 "$GMM_REPO/scripts/initial_pose_args.py" "$bag")
    # shellcheck disable=SC2086
    ROS_MASTER_URI="http://localhost:$port" ROS_LOG_DIR="$OUT/ros_logs" \
      roslaunch -p "$port" gmm_localization replay.launch bag:="$bag" map:="$OUT/map$sfx" \
      record:="$OUT/replay_$ds$sfx.bag" use_initial_pose:=true $args \
      >"$OUT/replay_$ds$sfx.log" 2>&1 || true
    sleep 2
    "$BIN/evaluate" recorded --bag "$OUT/replay_$ds$sfx.bag" --source-bag "$bag" \
      --dataset "$ds" "${scoring[@]}" --out "$OUT/eval_replay_$ds$sfx" \
      >"$OUT/eval_replay_$ds$sfx.log"
    DIRS+=("$OUT/eval_replay_$ds$sfx")
  fi
  # GMM_FULL_KEEP_BAGS=0: the drive's bag (about 18 GB) goes once scored; a rerun simulates it.
  [ "$KEEP_BAGS" = 1 ] || rm -f "$bag" "$OUT/$ds$sfx.done"
}

map_world ""
for ds in downtown snowy; do run_drive "$ds" "" perfect; done
if [ "$IMPERFECT" = 1 ]; then
  map_world _imperfect "${IMPERFECT_MAPPING[@]}"
  for ds in downtown snowy; do run_drive "$ds" _imperfect imperfect; done
fi

/usr/bin/python3 "$GMM_REPO/scripts/plot_evaluation.py" --out "$OUT/figures" "${DIRS[@]}"
cat "$OUT/figures/table1.md"
echo "Figures: $OUT/figures/"
