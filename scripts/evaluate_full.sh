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
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
cd "$GMM_REPO"

OUT="${GMM_FULL_DIR:-$GMM_WS/full}"
REPLAY="${GMM_FULL_REPLAY:-1}"
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

[ -f "$OUT/mapping.done" ] || {
  t "$BIN/simulate" "${TOWN[@]}" "${AZ[@]}" --pass mapping --kitti "$OUT/mapping" --kitti-every 2 --quiet
  touch "$OUT/mapping.done"
}
[ -f "$OUT/map.done" ] || {
  t "$BIN/build_map" --kitti "$OUT/mapping" --kitti-fields xyzi --output "$OUT/map" --overwrite
  touch "$OUT/map.done"
}
for ds in downtown snowy; do
  [ -f "$OUT/$ds.done" ] || {
    t "$BIN/simulate" "${TOWN[@]}" "${AZ[@]}" --pass "$ds" --bag "$OUT/$ds.bag" --quiet
    touch "$OUT/$ds.done"
  }
done

DIRS=()
for ds in downtown snowy; do
  t "$BIN/evaluate" bag --bag "$OUT/$ds.bag" --map "$OUT/map" --dataset "$ds" \
    --offset-scans "$OFFSETS" --out "$OUT/eval_$ds" | tee "$OUT/eval_$ds.log" | grep -E "^\|" || true
  DIRS+=("$OUT/eval_$ds")
done

if [ "$REPLAY" = 1 ]; then
  for ds in downtown snowy; do
    port=$(gmm_free_port)
    args=$(/usr/bin/python3 "$GMM_REPO/scripts/initial_pose_args.py" "$OUT/$ds.bag")
    # shellcheck disable=SC2086
    ROS_MASTER_URI="http://localhost:$port" ROS_LOG_DIR="$OUT/ros_logs" \
      roslaunch -p "$port" gmm_localization replay.launch bag:="$OUT/$ds.bag" map:="$OUT/map" \
      record:="$OUT/replay_$ds.bag" use_initial_pose:=true $args >"$OUT/replay_$ds.log" 2>&1 || true
    sleep 2
    "$BIN/evaluate" recorded --bag "$OUT/replay_$ds.bag" --source-bag "$OUT/$ds.bag" \
      --dataset "$ds" --out "$OUT/eval_replay_$ds" >"$OUT/eval_replay_$ds.log"
    DIRS+=("$OUT/eval_replay_$ds")
  done
fi

/usr/bin/python3 "$GMM_REPO/scripts/plot_evaluation.py" --out "$OUT/figures" "${DIRS[@]}"
cat "$OUT/figures/table1.md"
echo "Figures: $OUT/figures/"
