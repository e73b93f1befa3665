#!/usr/bin/env python3
"""Top-down view of a Gaussian mixture map, coloured by the number of Gaussians per cell
(the paper's Fig. 3: white, blue and purple for 0, 1 and 2), optionally with a second panel
of the mean height of each cell's highest component.

Usage:
  plot_map_components.py MAP_DIR_OR_CSV OUT.png [--mean-height] [--rows N] [--map-info PATH]
                         [--xlim X0,X1] [--ylim Y0,Y1] [--title TEXT]

MAP_DIR_OR_CSV is a map directory (map_info is run to export its cells) or a CSV written by
`map_info MAP --csv FILE`. --rows N cuts a long map into N strips along x (for a street);
--xlim/--ylim keep only the cells inside (map frame, metres). The printed shares count the
cells kept.
Needs the system python with matplotlib and numpy (PATH=/usr/bin:$PATH).
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

COLOURS = ["#ffffff", "#285adc", "#8c28a0", "#dc1e1e"]  # 0, 1, 2, 3 components (as map_info)


def find_map_info(explicit):
    if explicit:
        return explicit
    ws = os.environ.get("GMM_WS", os.path.join(os.path.dirname(__file__), "..", ".ws"))
    candidate = os.path.join(ws, "devel", "lib", "gmm_localization", "map_info")
    if os.path.exists(candidate):
        return candidate
    found = shutil.which("map_info")
    if found:
        return found
    sys.exit("plot_map_components: map_info not found; pass --map-info or set GMM_WS")


def load_cells(source, map_info):
    if os.path.isdir(source):
        with tempfile.TemporaryDirectory() as tmp:
            csv = os.path.join(tmp, "cells.csv")
            subprocess.run([map_info, source, "--no-verify", "--csv", csv], check=True,
                           stdout=subprocess.DEVNULL)
            return np.genfromtxt(csv, delimiter=",", names=True, filling_values=np.nan)
    return np.genfromtxt(source, delimiter=",", names=True, filling_values=np.nan)


def rasterize(cells):
    x, y = cells["x_m"], cells["y_m"]
    xs = np.unique(np.round(x, 3))
    res = np.min(np.diff(xs)) if len(xs) > 1 else 0.2
    ix = np.round((x - x.min()) / res).astype(int)
    iy = np.round((y - y.min()) / res).astype(int)
    shape = (iy.max() + 1, ix.max() + 1)
    k = np.zeros(shape)
    top = np.full(shape, np.nan)
    k[iy, ix] = cells["k"]
    means = np.vstack([cells["mu0"], cells["mu1"], cells["mu2"]])
    top[iy, ix] = np.nanmax(means, axis=0)
    extent = (x.min() - res / 2, x.max() + res / 2, y.min() - res / 2, y.max() + res / 2)
    return k, top, extent, res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("source")
    ap.add_argument("out")
    ap.add_argument("--mean-height", action="store_true")
    ap.add_argument("--rows", type=int, default=1)
    ap.add_argument("--map-info")
    ap.add_argument("--title", default="")
    ap.add_argument("--xlim")
    ap.add_argument("--ylim")
    a = ap.parse_args()
    cells = np.atleast_1d(load_cells(a.source, find_map_info(a.map_info)))
    for lim, col in ((a.xlim, "x_m"), (a.ylim, "y_m")):
        if lim:
            lo, hi = (float(v) for v in lim.split(","))
            cells = cells[(cells[col] >= lo) & (cells[col] <= hi)]
    if cells.size == 0:
        sys.exit("plot_map_components: no cell with data (inside the limits)")
    k, top, extent, res = rasterize(cells)
    counts = [int(np.sum(cells["k"] == i)) for i in range(4)]
    total = sum(counts)
    share = ", ".join(f"{i}: {100.0 * c / total:.1f}%" for i, c in enumerate(counts[1:], 1) if c or i < 3)
    print(f"cells with data: {total} ({share}); empty cells inside the extent: {int(np.sum(k == 0))}")

    panels = 2 if a.mean_height else 1
    rows = max(1, a.rows)
    width = k.shape[1]
    strip = int(np.ceil(width / rows))
    fig_w = 14.0
    axis_h = fig_w * 0.9 * k.shape[0] / strip  # equal-aspect axes fill ~90% of the width
    fig, axes = plt.subplots(rows * panels, 1, figsize=(fig_w, rows * panels * (axis_h + 0.6) + 0.8),
                             squeeze=False)
    cmap = ListedColormap(COLOURS)
    for r in range(rows):
        lo, hi = r * strip, min(width, (r + 1) * strip)
        x0 = extent[0] + lo * res
        sub_extent = (x0, x0 + (hi - lo) * res, extent[2], extent[3])
        ax = axes[r * panels][0]
        ax.imshow(k[:, lo:hi], origin="lower", cmap=cmap, vmin=-0.5, vmax=3.5, extent=sub_extent,
                  interpolation="nearest")
        ax.set_ylabel("y [m]")
        if a.mean_height:
            ax2 = axes[r * panels + 1][0]
            im = ax2.imshow(top[:, lo:hi], origin="lower", cmap="viridis", extent=sub_extent,
                            interpolation="nearest")
            ax2.set_ylabel("y [m]")
            fig.colorbar(im, ax=ax2, fraction=0.02, pad=0.01, label="highest mean [m]")
    axes[-1][0].set_xlabel("x [m]")
    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=c, edgecolor="0.5") for c in COLOURS[:3]]
    axes[0][0].legend(handles, ["0 Gaussians", "1 Gaussian", "2 Gaussians"], loc="upper right",
                      fontsize=8, framealpha=0.9)
    title = a.title or f"Gaussians per {res:.2f} m cell ({share} of {total} cells with data)"
    axes[0][0].set_title(title)
    fig.tight_layout()
    fig.savefig(a.out, dpi=150)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
