#!/usr/bin/env bash
# Reproduces docs/images/rviz_replay.png: launch/replay.launch with rviz (rviz/gmm_localization.rviz)
# under Xvfb, started from the bag's first ground truth pose, and a screenshot of the whole
# screen once the bag has played SHOT_AT_S seconds.
#
# Usage: scripts/rviz_screenshot.sh BAG MAP [OUT_PNG]
#   e.g. scripts/rviz_screenshot.sh .ws/demo/downtown.bag .ws/demo/map docs/images/rviz_replay.png
# Environment: SHOT_AT_S (bag seconds, default 24), RATE (playback rate, default 0.5: rviz renders
#   in software under Xvfb and shares the cores), SCREEN (default :97), PORT (ROS master, 11397),
#   SIZE (default 1280x800).
# Needs Xvfb and ImageMagick (import, convert). Everything it starts is stopped by pid at the end.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
gmm_source_ros

BAG="$(realpath "${1:?usage: rviz_screenshot.sh BAG MAP [OUT_PNG]}")"
MAP="$(realpath "${2:?usage: rviz_screenshot.sh BAG MAP [OUT_PNG]}")"
OUT="${3:-$GMM_REPO/docs/images/rviz_replay.png}"
SHOT_AT_S="${SHOT_AT_S:-24}"
RATE="${RATE:-0.5}"
SCREEN="${SCREEN:-:97}"
PORT="${PORT:-11397}"
SIZE="${SIZE:-1280x800}"
WORK="$(mktemp -d /tmp/gmm_rviz_shot.XXXXXX)"
export ROS_MASTER_URI="http://localhost:$PORT" ROS_HOME="$WORK/ros"

# The first ground truth pose of the bag (the replay starts localized there).
read -r T0 X Y Z YAW < <(/usr/bin/python3 - "$BAG" <<'EOF'
import math, sys
import rosbag
with rosbag.Bag(sys.argv[1]) as bag:
    for _, m, _ in bag.read_messages(topics=['/ground_truth/odom']):
        p, q = m.pose.pose.position, m.pose.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        print('%.6f %.4f %.4f %.4f %.6f' % (m.header.stamp.to_sec(), p.x, p.y, p.z, yaw))
        break
EOF
)

pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  sleep 3
  for pid in "${pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  rm -rf "$WORK"
}
trap cleanup EXIT

Xvfb "$SCREEN" -screen 0 "${SIZE}x24" +extension GLX -nolisten tcp >"$WORK/xvfb.log" 2>&1 &
pids+=($!)
sleep 2
DISPLAY="$SCREEN" roslaunch -p "$PORT" gmm_localization replay.launch bag:="$BAG" map:="$MAP" \
  use_initial_pose:=true initial_x:="$X" initial_y:="$Y" initial_z:="$Z" initial_yaw:="$YAW" \
  rate:="$RATE" delay:=10 play_args:=-q rviz:=true >"$WORK/replay.log" 2>&1 &
pids+=($!)

# Wait for the bag to reach T0 + SHOT_AT_S on /clock.
/usr/bin/python3 - "$T0" "$SHOT_AT_S" <<'EOF'
import sys, time
import rospy
from rosgraph_msgs.msg import Clock
target = float(sys.argv[1]) + float(sys.argv[2])
start = time.time()
rospy.init_node('rviz_screenshot_clock', anonymous=True)
while time.time() - start < 600:
    try:
        c = rospy.wait_for_message('/clock', Clock, timeout=5.0)
        if c.clock.to_sec() >= target:
            break
    except rospy.ROSException:
        pass
EOF
sleep 1
DISPLAY="$SCREEN" import -window root "$WORK/shot.png"
mkdir -p "$(dirname "$OUT")"
# A 256-colour PNG keeps the picture under 500 KB.
convert "$WORK/shot.png" -colors 256 PNG8:"$OUT"
echo "screenshot at bag time +${SHOT_AT_S} s: $OUT ($(du -h "$OUT" | cut -f1))"
