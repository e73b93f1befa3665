#!/usr/bin/env bash
# Real-time replays of a demo drive under CPU load, at several rates: is every scan answered or
# counted? For each rate it starts GMM_LOAD_WORKERS busy loops (default 4: with the stack that
# is a load of about 6 on 2 cores), runs launch/replay.launch at that rate on its own ROS master
# (a free port) recording the outputs, stops the load, scores the recording with
# `evaluate recorded`, and prints one table row:
#   scans in the bag, answered (a MatchStatus), counted as dropped (dropped_scans), neither,
#   accepted, latency stamp -> pose (median, p95), processing per scan (median, p95).
# Usage: scripts/replay_under_load.sh [DATASET] [RATE...]   (defaults: downtown 1 2 4)
# Needs the demo's bag and map (./scripts/demo.sh writes them to .ws/demo). GMM_LOAD_WORKERS=0
# replays on a quiet machine; GMM_REPLAY_ARGS adds replay.launch arguments (e.g.
# "config_dir:=DIR" for a matcher.yaml with registration/threads: 1).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
gmm_source_ros
DEMO="${GMM_DEMO_DIR:-$GMM_WS/demo}"
DATASET="${1:-downtown}"
shift || true
RATES=("$@")
[ "${#RATES[@]}" -gt 0 ] || RATES=(1 2 4)
WORKERS="${GMM_LOAD_WORKERS:-4}"
BAG="$DEMO/$DATASET.bag"
OUT="$GMM_WS/replay_under_load"
BIN="$GMM_DEVEL/lib/gmm_localization"
[ -f "$BAG" ] && [ -d "$DEMO/map" ] || { echo "no $BAG or $DEMO/map: run ./scripts/demo.sh" >&2; exit 1; }
mkdir -p "$OUT"
args=$(/usr/bin/python3 "$GMM_REPO/scripts/initial_pose_args.py" "$BAG")
duration=$(/usr/bin/python3 -c "import rosbag,sys; b=rosbag.Bag(sys.argv[1]); print(int(b.get_end_time()-b.get_start_time())+1)" "$BAG")

LOAD_PIDS=()
start_load() {
  local i
  for i in $(seq "$WORKERS"); do
    (while :; do :; done) &
    LOAD_PIDS+=("$!")
  done
}
stop_load() {
  [ "${#LOAD_PIDS[@]}" -gt 0 ] && kill "${LOAD_PIDS[@]}" 2>/dev/null || true
  LOAD_PIDS=()
}
trap stop_load EXIT

rows=()
for rate in "${RATES[@]}"; do
  rec="$OUT/${DATASET}_x${rate}.bag"
  rm -f "$rec" "$rec.active"
  port=$(gmm_free_port)
  start_load
  load_before=$(cut -d' ' -f1 /proc/loadavg)
  # shellcheck disable=SC2086
  ROS_MASTER_URI="http://localhost:$port" ROS_LOG_DIR="$OUT/ros_logs" \
    timeout --signal=INT --kill-after=20 $((duration + 180)) \
    roslaunch -p "$port" --screen gmm_localization replay.launch bag:="$BAG" map:="$DEMO/map" \
    rate:="$rate" record:="$rec" use_initial_pose:=true $args ${GMM_REPLAY_ARGS:-} \
    >"$OUT/${DATASET}_x${rate}.log" 2>&1 ||
    true
  load_after=$(cut -d' ' -f1 /proc/loadavg)
  stop_load
  for _ in $(seq 20); do [ -f "$rec" ] && break; sleep 0.5; done
  [ -f "$rec" ] || { tail -n 30 "$OUT/${DATASET}_x${rate}.log"; echo "no recording at rate $rate" >&2; exit 1; }
  "$BIN/evaluate" recorded --bag "$rec" --source-bag "$BAG" --dataset "$DATASET" \
    --out "$OUT/eval_${DATASET}_x${rate}" >"$OUT/eval_${DATASET}_x${rate}.log" 2>&1 ||
    { tail -n 20 "$OUT/eval_${DATASET}_x${rate}.log"; exit 1; }
  rows+=("$(/usr/bin/python3 - "$OUT/eval_${DATASET}_x${rate}/summary.json" "$rate" "$load_before" "$load_after" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
m = s.get("matching", s)
def g(*keys):
    for k in keys:
        for d in (m, s):
            if k in d:
                return d[k]
    return None
# matches.csv: one row per MatchStatus recorded (every answered scan, processed or skipped).
with open(sys.argv[1].replace("summary.json", "matches.csv")) as f:
    answered = sum(1 for _ in f) - 1
scans, dropped = g("scans"), g("dropped_scans")
lat, proc = g("latency_s") or {}, g("processing_ms") or {}
neither = scans - answered - dropped
print("| %sx | %s-%s | %d | %d | %d | %d | %d | %.0f / %.0f | %.0f / %.0f |" % (
    sys.argv[2], sys.argv[3], sys.argv[4], scans, answered, dropped, neither, g("accepted"),
    1000 * lat.get("p50", float("nan")), 1000 * lat.get("p95", float("nan")),
    proc.get("p50", float("nan")), proc.get("p95", float("nan"))))
EOF
)")
done

echo
echo "Replays of $DATASET under load ($WORKERS busy loops; $(nproc) cores; $(date -u +%F), $(git -C "$GMM_REPO" rev-parse --short HEAD)${GMM_REPLAY_ARGS:+; $GMM_REPLAY_ARGS}):"
echo
echo "| rate | load (1 min, start-end) | scans | answered | dropped (counted) | neither | accepted | latency stamp->pose median / p95 [ms] | processing median / p95 [ms] |"
echo "|---|---|---|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
