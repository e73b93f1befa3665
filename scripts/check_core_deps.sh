#!/usr/bin/env bash
# The core and the simulator stay free of ROS and PCL (DESIGN.md 2): fail on any such include.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
pattern='^\s*#\s*include\s*[<"](ros|pcl|pcl_ros|pcl_conversions|tf2|tf2_ros|nodelet|rosbag|sensor_msgs|geometry_msgs|nav_msgs|std_msgs|gmm_localization/ros)/'
if grep -rnE "$pattern" include/gmm_localization/core include/gmm_localization/sim src/core src/sim; then
  echo "check_core_deps: ROS/PCL include found in the ROS-free core or simulator (above)" >&2
  exit 1
fi
echo "check_core_deps: core and sim are free of ROS and PCL includes"
