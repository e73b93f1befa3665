#!/usr/bin/env python3
"""Top-down view of a Gaussian mixture map, coloured by the number of Gaussians per cell
(the paper's Fig. 3: white, blue and purple for 0, 1 and 2), optionally with a second panel
of the mean height of each cell's highest component; and, for the real-data check
(docs/real_data.md), an oblique view of the point cloud over that map (Fig. 3's rendering) and
the mixtures per class of cell written by `kitti_check cells`.

Usage:
  plot_map_components.py MAP_DIR_OR_CSV OUT.png [--mean-height] [--rows N] [--map-info PATH]
                         [--xlim X0,X1] [--ylim Y0,Y1] [--title TEXT] [--dpi N]
                         [--footprint-m M]
                         [--cloud CLOUD.bin --oblique OBLIQUE.png]
                         [--classes CELLS.csv --examples EXAMPLES.csv --classes-out OUT2.png]

MAP_DIR_OR_CSV is a map directory (map_info is run to export its cells) or a CSV written by
`map_info MAP --csv FILE`. --rows N cuts a long map into N strips along x (for a street);
--xlim/--ylim keep only the cells inside (map frame, metres). The printed shares count the
cells kept: cells with data by number of components, and empty (0-component) cells both inside
the drawn extent and inside the footprint (cells within --footprint-m of a cell with data, 1 m
by default: holes between observed cells, not the unobserved land around them).
--cloud: float32 records x,y,z[,class] in the map frame (kitti_check's cloud.bin has a class:
0 ground, 1 wall, 2 vegetation, 3 other, 4 below ground); --oblique draws the non-ground points
(brown to yellow by height) over the component map laid at the ground, like the paper's Fig. 3.
--classes/--examples (kitti_check's cells.csv and examples.csv) draw the class of each cell and
the example cells' column heights with their fitted mixtures.
Needs the system python with matplotlib and numpy (PATH=/usr/bin:$PATH); scipy for the
footprint (skipped without it).
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
CLASSES = ["ground", "wall", "vegetation", "other", "below ground"]
CLASS_COLOURS = ["#c8c8c8", "#d62728", "#2ca02c", "#1f77b4", "#ff7f0e"]


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


def grid_of(x, y):
    xs = np.unique(np.round(x, 3))
    res = np.min(np.diff(xs)) if len(xs) > 1 else 0.2
    ix = np.round((x - x.min()) / res).astype(int)
    iy = np.round((y - y.min()) / res).astype(int)
    extent = (x.min() - res / 2, x.max() + res / 2, y.min() - res / 2, y.max() + res / 2)
    return ix, iy, (iy.max() + 1, ix.max() + 1), extent, res


def rasterize(cells):
    ix, iy, shape, extent, res = grid_of(cells["x_m"], cells["y_m"])
    k = np.zeros(shape)
    top = np.full(shape, np.nan)
    k[iy, ix] = cells["k"]
    means = np.vstack([cells["mu0"], cells["mu1"], cells["mu2"]])
    top[iy, ix] = np.nanmax(means, axis=0)
    return k, top, extent, res


def footprint_share(k, res, footprint_m):
    """Share of empty cells among the cells within footprint_m of a cell with data."""
    try:
        from scipy import ndimage
    except ImportError:
        return None
    r = max(1, int(round(footprint_m / res)))
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    near = ndimage.binary_dilation(k > 0, structure=(xx * xx + yy * yy) <= r * r)
    inside = int(np.sum(near))
    return inside, int(np.sum(near & (k == 0)))


def top_down(a, cells):
    k, top, extent, res = rasterize(cells)
    counts = [int(np.sum(cells["k"] == i)) for i in range(4)]
    total = sum(counts)
    share = ", ".join(f"{i}: {100.0 * c / total:.1f}%" for i, c in enumerate(counts[1:], 1) if c or i < 3)
    empty = int(np.sum(k == 0))
    print(f"cells with data: {total} ({share}); empty cells inside the extent: {empty} "
          f"({100.0 * empty / k.size:.1f}% of {k.size})")
    fp = footprint_share(k, res, a.footprint_m)
    if fp:
        print(f"footprint (within {a.footprint_m:g} m of data): {fp[0]} cells, "
              f"0: {100.0 * fp[1] / fp[0]:.1f}%, 1: {100.0 * counts[1] / fp[0]:.1f}%, "
              f"2: {100.0 * counts[2] / fp[0]:.1f}%")

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
    auto = f"Gaussians per {res:.2f} m cell ({share} of {total} cells with data)"
    title = f"{a.title}\n{auto}" if a.title else auto
    axes[0][0].set_title(title)
    fig.tight_layout()
    fig.savefig(a.out, dpi=a.dpi)
    plt.close(fig)
    print(f"wrote {a.out}")


def load_cloud(path):
    raw = np.fromfile(path, dtype=np.float32)
    fields = 4 if raw.size % 4 == 0 and raw.size % 3 != 0 else 3
    if raw.size % 4 == 0 and raw.size % 3 == 0:
        fields = 4 if np.all(np.isin(raw.reshape(-1, 4)[:, 3], [0, 1, 2, 3, 4])) else 3
    return raw.reshape(-1, fields)


def oblique(a, cells):
    """Fig. 3's view: the cloud's structure over the component map laid at the ground."""
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401

    cloud = load_cloud(a.cloud)
    x, y, z, km = cells["x_m"], cells["y_m"], cells["k"], cells["k"]
    lowest = np.nanmin(np.vstack([cells["mu0"], cells["mu1"], cells["mu2"]]), axis=0)
    ground = np.nanpercentile(lowest, 5)
    if cloud.shape[1] == 4:
        structure = cloud[(cloud[:, 3] != 0) & (cloud[:, 3] != 4)]
        ground = np.median(cloud[cloud[:, 3] == 0, 2])
    else:
        structure = cloud[cloud[:, 2] > ground + 0.3]
    keep = np.ones(len(structure), bool)
    for lim, col in ((a.xlim, 0), (a.ylim, 1)):
        if lim:
            lo, hi = (float(v) for v in lim.split(","))
            keep &= (structure[:, col] >= lo) & (structure[:, col] <= hi)
    structure = structure[keep & (structure[:, 2] < ground + 8.0)]
    fig = plt.figure(figsize=(12, 8))
    # Axes larger than the figure: the 3D box then fills it (set_box_aspect's zoom clips data).
    ax = fig.add_axes([-0.14, -0.22, 1.28, 1.32], projection="3d", computed_zorder=False)
    ax.scatter(x, y, np.full_like(x, ground - 0.05), c=np.array(COLOURS)[km.astype(int)],
               marker="s", s=2.0, linewidths=0, depthshade=False, zorder=1)
    ax.scatter(structure[:, 0], structure[:, 1], structure[:, 2], c=structure[:, 2],
               cmap="YlOrBr_r", vmin=ground, vmax=ground + 6.0, s=0.8, linewidths=0,
               depthshade=False, zorder=2)
    ax.view_init(elev=32, azim=-125)
    ax.grid(False)
    xs = [float(v) for v in a.xlim.split(",")] if a.xlim else [x.min(), x.max()]
    ys = [float(v) for v in a.ylim.split(",")] if a.ylim else [y.min(), y.max()]
    ax.set_xlim(*xs)
    ax.set_ylim(*ys)
    ax.set_zlim(ground - 0.5, ground + 8.0)
    ax.set_box_aspect((xs[1] - xs[0], ys[1] - ys[0], 8.5))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zticks([])
    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=c, edgecolor="0.5") for c in COLOURS[:3]]
    handles.append(plt.Line2D([], [], marker="o", color="#c47a1a", linestyle="", markersize=4))
    fig.legend(handles, ["0 Gaussians", "1 Gaussian", "2 Gaussians", "points above ground"],
               loc="upper left", bbox_to_anchor=(0.01, 0.95), fontsize=8)
    fig.suptitle(a.title or "Point cloud (brown to yellow by height) over the Gaussian mixture map")
    fig.savefig(a.oblique, dpi=a.dpi)
    plt.close(fig)
    print(f"wrote {a.oblique}")


def mixture_pdf(row, z):
    p = np.zeros_like(z)
    for j in range(3):
        w, mu, s = row[f"w{j}"], row[f"mu{j}"], row[f"sigma{j}"]
        if np.isfinite(w) and np.isfinite(s) and s > 0:
            p += w * np.exp(-0.5 * ((z - mu) / s) ** 2) / (s * np.sqrt(2 * np.pi))
    return p


def classes(a):
    cells = np.genfromtxt(a.classes, delimiter=",", names=True, dtype=None, encoding="utf-8")
    examples = []
    if a.examples:
        examples = np.atleast_1d(np.genfromtxt(a.examples, delimiter=",", names=True, dtype=None,
                                               encoding="utf-8"))
    cls = np.array([CLASSES.index(c) for c in cells["class"]])
    ix, iy, shape, extent, res = grid_of(cells["x_m"], cells["y_m"])
    img = np.full(shape, -1)
    img[iy, ix] = cls
    n_ex = len(examples)
    cols = 5
    ex_rows = int(np.ceil(n_ex / cols))
    fig = plt.figure(figsize=(15, 7.5 + 2.9 * ex_rows))
    gs = fig.add_gridspec(1 + ex_rows, cols, height_ratios=[7.5] + [2.9] * ex_rows)
    ax = fig.add_subplot(gs[0, :])
    cmap = ListedColormap(["#ffffff"] + CLASS_COLOURS)
    ax.imshow(img, origin="lower", cmap=cmap, vmin=-1.5, vmax=len(CLASSES) - 0.5, extent=extent,
              interpolation="nearest")
    if a.xlim:
        ax.set_xlim(*(float(v) for v in a.xlim.split(",")))
    if a.ylim:
        ax.set_ylim(*(float(v) for v in a.ylim.split(",")))
    for i, e in enumerate(examples):
        ax.plot(e["x_m"], e["y_m"], "o", mfc="none", mec="k", ms=9, mew=1.2)
        ax.annotate(chr(ord("a") + i), (e["x_m"], e["y_m"]), xytext=(5, 5),
                    textcoords="offset points", fontsize=9, weight="bold")
    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=c, edgecolor="0.5") for c in CLASS_COLOURS]
    counts = [int(np.sum(cls == i)) for i in range(len(CLASSES))]
    ax.legend(handles, [f"{n} ({c} cells)" for n, c in zip(CLASSES, counts)], loc="upper right",
              fontsize=8, framealpha=0.9)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Class of each map cell from its points (circles: example cells below)")
    for i, e in enumerate(examples):
        axe = fig.add_subplot(gs[1 + i // cols, i % cols])
        zs = np.array([float(v) for v in str(e["z"]).split(";") if v != ""])
        zn = np.array([float(v) for v in str(e["neighbour_z"]).split(";") if v not in ("", "nan")])
        lo = min(zs.min(), np.nanmin([e["mu0"], e["mu1"]])) - 0.5
        hi = max(zs.max(), np.nanmax([e["mu0"], e["mu1"]])) + 0.5
        grid = np.linspace(lo, hi, 400)
        bins = np.arange(lo, hi + 0.1, 0.1)
        # Counts scaled like a density of the own column (neighbours stacked, lighter).
        scale = 1.0 / (len(zs) * 0.1)
        own, _ = np.histogram(zs, bins)
        near, _ = np.histogram(zn[(zn >= lo) & (zn <= hi)], bins)
        axe.barh(bins[:-1], own * scale, height=0.1, align="edge", color="0.45",
                 label="own column")
        axe.barh(bins[:-1], near * scale * 0.5, height=0.1, align="edge", left=own * scale,
                 color="0.82", label="8 neighbours (x 0.5)")
        axe.plot(mixture_pdf(e, grid), grid, color=COLOURS[min(int(e["k"]), 3)], lw=1.6,
                 label="mixture")
        axe.axhline(e["ground_z"], color="k", lw=0.6, ls=":")
        axe.set_title(f"{chr(ord('a') + i)}: {e['class']}, K={int(e['k'])}, {len(zs)} + {len(zn)} pts",
                      fontsize=9)
        if i == 0:
            axe.legend(fontsize=6, loc="upper right")
        axe.tick_params(labelsize=7)
        if i % cols == 0:
            axe.set_ylabel("z [m]", fontsize=8)
        axe.set_xlabel("density [1/m]", fontsize=7)
    fig.tight_layout()
    fig.savefig(a.classes_out, dpi=a.dpi)
    plt.close(fig)
    print(f"wrote {a.classes_out}")


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
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--footprint-m", type=float, default=1.0)
    ap.add_argument("--cloud")
    ap.add_argument("--oblique")
    ap.add_argument("--classes")
    ap.add_argument("--examples")
    ap.add_argument("--classes-out")
    a = ap.parse_args()
    cells = np.atleast_1d(load_cells(a.source, find_map_info(a.map_info)))
    for lim, col in ((a.xlim, "x_m"), (a.ylim, "y_m")):
        if lim:
            lo, hi = (float(v) for v in lim.split(","))
            cells = cells[(cells[col] >= lo) & (cells[col] <= hi)]
    if cells.size == 0:
        sys.exit("plot_map_components: no cell with data (inside the limits)")
    top_down(a, cells)
    if a.oblique:
        if not a.cloud:
            sys.exit("plot_map_components: --oblique needs --cloud")
        oblique(a, cells)
    if a.classes:
        if not a.classes_out:
            sys.exit("plot_map_components: --classes needs --classes-out")
        classes(a)


if __name__ == "__main__":
    main()
