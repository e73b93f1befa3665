#!/usr/bin/env bash
# Dependency rules of the ROS-free core and simulator (DESIGN.md 2), checked on every include:
#  1. core/ and sim/ include no ROS or PCL header;
#  2. each stage folder of the core includes only the stages below it in the data flow:
#       common <- map <- mapping
#                 map <- raster <- matching
#       common <- filter
#       localization <- everything above
#     (a header of a stage later in the list is a back edge and fails the check);
#  3. the simulator includes only core/common.
# Usage: scripts/check_core_deps.sh [ROOT]  (ROOT defaults to the repository; the tests point it
# at a copy with a deliberate back edge to show that the check fails).
set -euo pipefail
root="${1:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}"
cd "$root"
status=0

ros_pattern='^\s*#\s*include\s*[<"](ros|pcl|pcl_ros|pcl_conversions|tf2|tf2_ros|nodelet|rosbag|sensor_msgs|geometry_msgs|nav_msgs|std_msgs|gmm_localization/ros)/'
if grep -rnE "$ros_pattern" include/gmm_localization/core include/gmm_localization/sim src/core src/sim; then
  echo "check_core_deps: ROS/PCL include found in the ROS-free core or simulator (above)" >&2
  status=1
fi

# Allowed stage dependencies (besides the stage itself).
declare -A allowed=(
  [common]=""
  [map]="common"
  [mapping]="common map"
  [raster]="common map"
  [matching]="common map raster"
  [filter]="common"
  [localization]="common map raster matching filter"
)
stages="${!allowed[*]}"
for dir in include/gmm_localization/core src/core; do
  for stage_dir in "$dir"/*/; do
    stage=$(basename "$stage_dir")
    if [ -z "${allowed[$stage]+x}" ]; then
      echo "check_core_deps: $stage_dir is not a known stage folder ($stages)" >&2
      status=1
      continue
    fi
    while IFS=: read -r file line text; do
      target=$(sed -E 's#.*gmm_localization/core/([a-z_]+)/.*#\1#' <<<"$text")
      [ "$target" = "$stage" ] && continue
      case " ${allowed[$stage]} " in
        *" $target "*) ;;
        *) echo "check_core_deps: $file:$line: $stage includes $target (allowed: ${allowed[$stage]:-none})" >&2
           status=1 ;;
      esac
    done < <(grep -rnE '^\s*#\s*include\s*"gmm_localization/core/' "$stage_dir" || true)
  done
  # No loose files beside the stage folders.
  loose=$(find "$dir" -maxdepth 1 -type f | head -5)
  if [ -n "$loose" ]; then
    echo "check_core_deps: files outside a stage folder: $loose" >&2
    status=1
  fi
done

while IFS=: read -r file line text; do
  target=$(sed -E 's#.*gmm_localization/core/([a-z_]+)/.*#\1#' <<<"$text")
  if [ "$target" != common ]; then
    echo "check_core_deps: $file:$line: the simulator includes core/$target (allowed: common)" >&2
    status=1
  fi
done < <(grep -rnE '^\s*#\s*include\s*"gmm_localization/core/' include/gmm_localization/sim src/sim || true)

if [ "$status" = 0 ]; then
  echo "check_core_deps: core and sim are free of ROS and PCL; stage includes follow the data flow"
fi
exit $status
