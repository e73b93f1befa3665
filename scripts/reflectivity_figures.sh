#!/usr/bin/env bash
# Regenerates docs/figures/fig2_reflectivity_clear_snowy.png (the paper's Fig. 2: the same
# streets' ground reflectivity in clear weather and in snow) and, with GMM_FIG10=1 (default),
# docs/figures/fig10_methods_downtown.png (Fig. 10 for the height, reflectivity and fused
# methods on one drive), from the repository's own tools, in a small town (250 m, a 500 m route):
#   1. simulate the mapping pass and the snowy pass over the whole route as KITTI scans
#      (deskewed, with the truth poses; 0.66 deg azimuth, every 2nd scan);
#   2. build_map --layer reflectivity from each (clear: the mapping pass; snow: the snowy pass);
#   3. scripts/plot_reflectivity_map.py draws both side by side (the area: --center auto, the
#      40 m square with the most lane paint in the clear map that both maps cover);
#   4. (GMM_FIG10=1) the height map too, a 20 s Downtown drive (rosbag, 1.33 deg azimuth) and
#      `evaluate bag --method height|reflectivity|fused` on it; scripts/plot_evaluation.py
#      overlays the three runs.
# Usage: reflectivity_figures.sh [WORK_DIR]   (default $GMM_WS/reflectivity_figures; on 2 cores
#   about 40 s for Fig. 2 and 45 s more for Fig. 10, 0.5 GB of scans and a 110 MB bag in
#   WORK_DIR). GMM_BUILD_LOCK=FILE runs each tool under `flock FILE` (a machine shared with builds
#   or timed benchmarks). The reflectivity run of Fig. 10 varies a little from run to run (its
#   global searches' wall time decides which scan restarts the tracking; docs/evaluation.md).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
gmm_source_ros
cd "$GMM_REPO"

WORK="${1:-$GMM_WS/reflectivity_figures}"
FIG10="${GMM_FIG10:-1}"
BIN="$GMM_DEVEL/lib/gmm_localization"
FIGURES="$GMM_REPO/docs/figures"
LOCK=()
[ -n "${GMM_BUILD_LOCK:-}" ] && LOCK=(flock "$GMM_BUILD_LOCK")
TOWN=(--town-size 250 --route-length 400)
SCANS=(--azimuth-step 0.66 --kitti-every 2 --quiet)
mkdir -p "$WORK" "$FIGURES"

for pass in mapping snowy; do
  rm -rf "${WORK:?}/$pass" "$WORK/refl_$pass"
  "${LOCK[@]}" "$BIN/simulate" "${TOWN[@]}" --pass "$pass" "${SCANS[@]}" --kitti "$WORK/$pass"
  "${LOCK[@]}" "$BIN/build_map" --kitti "$WORK/$pass" --kitti-fields xyzi --layer reflectivity \
    --output "$WORK/refl_$pass" --overwrite --quiet >"$WORK/build_map_refl_$pass.log"
done
/usr/bin/python3 scripts/plot_reflectivity_map.py "$WORK/refl_mapping" "$WORK/refl_snowy" \
  --center auto --size 40 \
  --labels "clear: map from the mapping pass,snow: map from the snowy pass (same streets)" \
  --title "Ground reflectivity of the same intersection in clear weather and in snow (simulated)" \
  --out "$FIGURES/fig2_reflectivity_clear_snowy.png"
[ "$FIG10" = 1 ] || exit 0

# Fig. 10 for the three methods: the map (height + reflectivity layer) from the mapping pass.
MAP="$WORK/map"
rm -rf "$MAP" "$WORK"/eval_*
"${LOCK[@]}" "$BIN/build_map" --kitti "$WORK/mapping" --kitti-fields xyzi --output "$MAP" \
  --overwrite --quiet >"$WORK/build_map_height.log"
mv "$WORK/refl_mapping" "$MAP/reflectivity"
"${LOCK[@]}" "$BIN/simulate" "${TOWN[@]}" --pass downtown --start-offset 30 --duration 20 \
  --azimuth-step 1.33 --bag "$WORK/downtown.bag" --quiet
for method in height reflectivity fused; do
  rc=0
  "${LOCK[@]}" "$BIN/evaluate" bag --bag "$WORK/downtown.bag" --map "$MAP" --dataset downtown \
    --method "$method" --offset-scans 0 --quiet --out "$WORK/eval_$method" \
    >"$WORK/eval_$method.log" 2>&1 || rc=$?
  # 3: never localized (no data): a result, drawn as such; anything else is a failure.
  [ "$rc" = 0 ] || [ "$rc" = 3 ] || { tail -n 20 "$WORK/eval_$method.log"; exit 1; }
  grep -E "^\| this run|^Matching" "$WORK/eval_$method.log" || true
done
/usr/bin/python3 scripts/plot_evaluation.py --out "$WORK/figures" "$WORK"/eval_height \
  "$WORK"/eval_reflectivity "$WORK"/eval_fused
cp "$WORK/figures/fig10_methods_downtown.png" "$FIGURES/"
echo "wrote $FIGURES/fig10_methods_downtown.png"
