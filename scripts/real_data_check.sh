#!/usr/bin/env bash
# Real-data checks (the map and the registration on real scans; docs/real_data.md), one command:
#  1. a Gaussian mixture map from the five KITTI 07 keyframes, each cell classed ground / wall /
#     vegetation / other / below ground from its points, the mixtures per class (tables) and
#     PNGs: the paper's Fig. 3 view (top-down and oblique) and the example cells;
#  2. the same top-down view and component shares for the simulated demo map;
#  3. leave-one-out registration: a map from four keyframes, the fifth registered from seeded
#     random offsets (paper window and tracking window) by our search and by PCL NDT and GICP
#     from the same offsets (the registration benchmark's peers, its settings), then the peers
#     again with tighter convergence settings (fewer offsets), and a figure of the errors.
# Prints markdown tables; writes them and the CSV files to $WORK and the PNGs to $IMAGES.
#
# Environment (defaults):
#   KITTI_DIR     ../shared/data/real/kitti07_keyframes (relative to the repository)
#   DEMO_MAP      $GMM_DEMO_DIR/map, default .ws/demo/map as demo.sh writes it (skipped when absent)
#   WORK          $GMM_WS/real_data
#   IMAGES        docs/images
#   OFFSETS       100 offsets per keyframe and window;  TUNED_OFFSETS 20 for the tuned peers
#   GMM_SKIP_BUILD=1  do not build (kitti_check and map_info must exist)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
KITTI_DIR="${KITTI_DIR:-$GMM_REPO/../shared/data/real/kitti07_keyframes}"
DEMO_MAP="${DEMO_MAP:-${GMM_DEMO_DIR:-$GMM_WS/demo}/map}"
WORK="${WORK:-$GMM_WS/real_data}"
IMAGES="${IMAGES:-$GMM_REPO/docs/images}"
OFFSETS="${OFFSETS:-100}"
TUNED_OFFSETS="${TUNED_OFFSETS:-20}"
BIN="$GMM_DEVEL/lib/gmm_localization"
PLOT="$GMM_REPO/scripts/plot_map_components.py"

if [ ! -f "$KITTI_DIR/graph.txt" ]; then
  echo "real_data_check: no keyframes at $KITTI_DIR (see ../shared/data/real/README.md)" >&2
  exit 1
fi
if [ -z "${GMM_SKIP_BUILD:-}" ]; then
  "$GMM_REPO/scripts/install_deps.sh" >&2
  mkdir -p "$GMM_WS"
  "$GMM_REPO/scripts/build.sh" kitti_check map_info >"$GMM_WS/real_data_build.log" 2>&1 ||
    { tail -n 40 "$GMM_WS/real_data_build.log" >&2; exit 1; }
fi
mkdir -p "$WORK" "$IMAGES"

echo "# Real-data check, $(date +%Y-%m-%d): $(cd "$GMM_REPO" && git rev-parse --short HEAD 2>/dev/null || echo '?')"
echo
echo "command: scripts/real_data_check.sh (KITTI_DIR=$KITTI_DIR OFFSETS=$OFFSETS TUNED_OFFSETS=$TUNED_OFFSETS)"
echo

# 1. Mixtures on real ground, walls and vegetation.
"$BIN/kitti_check" cells --data "$KITTI_DIR" --work "$WORK/cells" | tee "$WORK/cells.md"
echo
echo "## Components per cell (Fig. 3), KITTI 07 map of all five keyframes"
echo
echo '```'
python3 "$PLOT" "$WORK/cells/map_all" "$IMAGES/map_components_kitti07.png" --dpi 100 \
  --xlim=-30,40 --ylim=-32,60 \
  --title "KITTI 07 keyframes, central 70 m x 92 m of the map"
echo "whole map:"
python3 "$PLOT" "$WORK/cells/map_all" "$WORK/map_components_kitti07_full.png" --dpi 60
python3 "$PLOT" "$WORK/cells/map_all" "$WORK/unused_top.png" --dpi 90 \
  --xlim=-15,25 --ylim=-15,45 --cloud "$WORK/cells/cloud.bin" --oblique "$IMAGES/kitti_fig3_view.png" \
  --title "KITTI 07 keyframes: points above ground over the Gaussian mixture map (Fig. 3 view)" >/dev/null
python3 "$PLOT" "$WORK/cells/map_all" "$WORK/unused_top.png" --dpi 100 --xlim=-30,40 --ylim=-32,60 \
  --classes "$WORK/cells/cells.csv" --examples "$WORK/cells/examples.csv" \
  --classes-out "$IMAGES/kitti_cell_classes.png" >/dev/null
echo '```'

# 2. The simulated demo map.
if [ -f "$DEMO_MAP/manifest.gmm" ]; then
  echo
  echo "## Components per cell (Fig. 3), simulated demo map $DEMO_MAP"
  echo
  echo '```'
  "$BIN/map_info" "$DEMO_MAP" --no-verify --csv "$WORK/demo_cells.csv" >/dev/null
  python3 "$PLOT" "$WORK/demo_cells.csv" "$IMAGES/map_components_demo.png" --dpi 80 \
    --title "Simulated demo town (mapping pass)"
  echo "zoom (x 330-430 m, y 430-530 m):"
  python3 "$PLOT" "$WORK/demo_cells.csv" "$IMAGES/map_components_demo_zoom.png" --dpi 100 \
    --xlim=330,430 --ylim=430,530 --title "Simulated demo town, zoom on x 330-430 m, y 430-530 m"
  echo '```'
else
  echo "(no demo map at $DEMO_MAP: skipped)"
fi

# 3. Leave-one-out registration, ours and the peers with the benchmark's settings...
echo
"$BIN/kitti_check" register --data "$KITTI_DIR" --work "$WORK/loo" --offsets "$OFFSETS" \
  2>"$WORK/loo.log" | tee "$WORK/register.md"
# ... and the peers alone with tighter convergence (a finer stop and more iterations).
echo
echo "# Peers with tighter convergence (NDT resolution 2 m, epsilon 1e-4, 200 iterations)"
echo
"$BIN/kitti_check" register --data "$KITTI_DIR" --work "$WORK/loo_tuned" --offsets "$TUNED_OFFSETS" \
  --no-ours --ndt-resolution 2.0 --peer-epsilon 0.0001 --peer-iterations 200 \
  2>"$WORK/loo_tuned.log" | tee "$WORK/register_tuned_peers.md"

python3 - "$WORK/loo/trials.csv" "$IMAGES/kitti_registration.png" "$TUNED_OFFSETS" <<'EOF'
# Fig. 8-style view of the leave-one-out registrations: error after registration against the
# initial offset, per matcher, paper window; and success per held-out keyframe.
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

t = np.genfromtxt(sys.argv[1], delimiter=",", names=True, dtype=None, encoding="utf-8")
matchers = ["ours", "PCL NDT", "PCL GICP"]
colours = {"ours": "#285adc", "PCL NDT": "#dc7a1e", "PCL GICP": "#2ca02c"}
windows = [w for w in dict.fromkeys(t["window"]) if w != "SLAM pose"]
fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
for ax, w in zip(axes[:2], windows):
    for m in matchers:
        s = t[(t["window"] == w) & (t["matcher"] == m)]
        if len(s) == 0:
            continue
        err = np.clip(s["error_m"], 1e-3, None)
        ax.scatter(s["offset_m"], err, s=6, alpha=0.6, color=colours[m],
                   label=f"{m}: {100.0 * s['success'].mean():.0f}% within 0.5 m, 1 deg")
    ax.axhline(0.5, color="k", lw=0.7, ls="--")
    ax.set_yscale("log")
    ax.set_xlabel("initial offset [m]")
    ax.set_ylabel("horizontal error after registration [m]")
    ax.set_title(w.replace(";", ","), fontsize=10)
    ax.legend(fontsize=8, loc="lower right")
ax = axes[2]
keys = sorted(set(int(k) for k in t["keyframe"]))
width = 0.27
w0 = windows[0]
for i, m in enumerate(matchers):
    rates = []
    for k in keys:
        s = t[(t["window"] == w0) & (t["matcher"] == m) & (t["keyframe"] == k)]
        rates.append(100.0 * s["success"].mean() if len(s) else np.nan)
    ax.bar(np.array(keys) + (i - 1) * width, rates, width, color=colours[m], label=m)
ax.set_xticks(keys)
ax.set_xlabel("held-out keyframe")
ax.set_ylabel("success [%] (paper window)")
ax.set_ylim(0, 125)
ax.set_title("success per held-out keyframe, offsets within 10 m / 15 deg", fontsize=10)
ax.legend(fontsize=8, ncol=3, loc="upper center")
fig.suptitle("KITTI 07 keyframes, leave-one-out: map from four keyframes, the fifth registered")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=100)
print(f"wrote {sys.argv[2]}")

# The benchmark-settings run on the offsets the tuned peers used (the first N of each keyframe
# and window: the same seeds), so both tables compare like with like.
n = int(sys.argv[3])
print(f"\n## Benchmark settings on the tuned run's offsets (the first {n} per keyframe and window)\n")
print("| window | matcher | success <0.5 m, <1 deg |\n|---|---|---|")
for w in windows:
    for m in matchers:
        ok = runs = 0
        for k in keys:
            s = t[(t["window"] == w) & (t["matcher"] == m) & (t["keyframe"] == k)][:n]
            ok += int(s["success"].sum())
            runs += len(s)
        if runs:
            print(f"| {w.replace(';', ',')} | {m} | {ok}/{runs} ({100.0 * ok / runs:.0f}%) |")
EOF
rm -f "$WORK/unused_top.png"
echo
echo "tables: $WORK/{cells,register,register_tuned_peers}.md; trials: $WORK/loo/trials.csv"
echo "images: $IMAGES/{map_components_kitti07,map_components_demo,map_components_demo_zoom,kitti_fig3_view,kitti_cell_classes,kitti_registration}.png"
