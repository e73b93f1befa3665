#!/usr/bin/env python3
"""Orthographic ground-reflectivity image of a map's reflectivity layer (the paper's Fig. 2):
each 20 cm cell drawn grey by the mean intensity of its ground returns, for one square area;
with two or more maps, side by side (e.g. the same streets in clear weather and in snow).

Usage:
  plot_reflectivity_map.py MAP [MAP ...] --out OUT.png [--center X,Y|auto] [--size M]
                           [--labels A,B] [--title TEXT] [--vmax I] [--scale-bar M] [--dpi N]

MAP is a reflectivity map directory (`build_map --layer reflectivity --output DIR`, by
convention MAP/reflectivity beside a height map) or a CSV written by `map_info DIR --csv FILE`
(read with plot_map_components.py's reader; a CSV has no manifest, so build_map's default 0.02 m
per intensity unit is assumed). A map directory is read directly, only the tiles
that overlap the area: the tile format is documented in include/gmm_localization/core/map/
map_format.h (manifest version 1-3, tile version 1), and this reader checks magic, versions,
sizes and the tile CRC-32 but not the physical bounds the C++ reader checks. A height map is
refused (its cells hold heights, not intensities).

--center X,Y and --size M (default 40) give the square area (map frame, metres). --center auto
picks the square where the first map has the most bright cells (lane paint: mean intensity
>= --paint, default 60) among cells every map has data in, i.e. where a difference in the
paint would show. Each cell's value is the weighted mean of its mixture's components divided
by the layer's metres per intensity unit (0.02 m by default), i.e. the mean intensity (0-255)
of its ground returns; cells without ground returns are drawn in a dark blue.
Needs the system python with numpy and matplotlib (/usr/bin/python3).
"""
import argparse
import os
import struct
import sys
import zlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LinearSegmentedColormap  # noqa: E402

NO_DATA = "#1c2a4a"  # cells without ground returns
SLOTS = 3  # kMaxMixtureComponents
LOG_SIGMA = (np.log(1e-4), np.log(1e4))


class Reader:
    """Little-endian fields in order, as map_format_bytes.h's ByteReader."""

    def __init__(self, data, source):
        self.data, self.pos, self.source = data, 0, source

    def take(self, fmt):
        size = struct.calcsize(fmt)
        if self.pos + size > len(self.data):
            sys.exit(f"plot_reflectivity_map: {self.source}: truncated")
        value = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += size
        return value[0] if len(value) == 1 else value

    def string(self):
        n = self.take("<I")
        s = self.data[self.pos:self.pos + n].decode("utf-8", "replace")
        self.pos += n
        return s


def checked(path, magic):
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 12 or data[:4] != magic:
        sys.exit(f"plot_reflectivity_map: {path}: not a GMM {'manifest' if magic == b'GMMM' else 'tile'}")
    if zlib.crc32(data[:-4]) & 0xFFFFFFFF != struct.unpack_from("<I", data, len(data) - 4)[0]:
        sys.exit(f"plot_reflectivity_map: {path}: CRC-32 mismatch (corrupted)")
    return data


def read_manifest(map_dir):
    path = os.path.join(map_dir, "manifest.gmm")
    r = Reader(checked(path, b"GMMM"), path)
    r.take("<I")
    version = r.take("<H")
    if not 1 <= version <= 3:
        sys.exit(f"plot_reflectivity_map: {path}: manifest version {version} not in 1..3")
    r.take("<H")
    m = {"resolution": r.take("<d"), "tile_size": r.take("<I"), "origin": r.take("<dd")}
    r.take("<B")
    r.string()  # georeference: flag, datum
    if version >= 2:
        r.take("<BB")
    r.take("<ddd")
    m["provenance"] = r.string()
    layer = r.take("<B") if version >= 3 else 0
    if layer != 1:
        sys.exit(f"plot_reflectivity_map: {map_dir} is a height map, not a reflectivity layer "
                 "(build_map --layer reflectivity --output MAP/reflectivity)")
    m["metres_per_unit"] = r.take("<d")
    r.take("<dddd")
    m["tiles"] = []
    for _ in range(r.take("<I")):
        tx, ty = r.take("<ii")
        name = r.string()
        r.take("<QIff4I")
        m["tiles"].append((tx, ty, name))
    return m


def planes(raw, pos, n):
    """n u16 codes stored as a plane of low bytes then a plane of high bytes."""
    a = np.frombuffer(raw, np.uint8, 2 * n, pos).astype(np.uint16)
    return a[:n] | (a[n:] << 8), pos + 2 * n


def tile_mean_intensity(path, size_expected):
    """(tx, ty, S x S array of the weighted mean component value [m], NaN where empty)."""
    data = checked(path, b"GMMT")
    (version, flags, tx, ty, size, total, base, quantum, raw_bytes,
     stored_bytes) = struct.unpack_from("<HHiiIIddII", data, 4)
    if version != 1 or size != size_expected or stored_bytes + 52 != len(data):
        sys.exit(f"plot_reflectivity_map: {path}: unsupported or inconsistent tile")
    stored = data[48:48 + stored_bytes]
    raw = zlib.decompress(stored) if flags & 1 else stored
    n = size * size
    k = (np.frombuffer(raw, np.uint8, (n + 3) // 4).repeat(4)[:n] >> (2 * (np.arange(n) % 4))) & 3
    pos = (n + 3) // 4
    means, weights = [], []
    for j in range(SLOTS):  # slot j holds the j-th component of every cell with K > j
        codes, pos = planes(raw, pos, int(np.sum(k > j)))
        means.append(base + quantum * np.cumsum(codes, dtype=np.uint16).astype(np.float64))
    for j in range(SLOTS):  # sigmas: not needed for the image
        pos = planes(raw, pos, int(np.sum(k > j)))[1]
    for j in range(SLOTS):  # weights, cells with K >= 2 only
        codes, pos = planes(raw, pos, int(np.sum((k > j) & (k >= 2))))
        weights.append(np.exp(np.log(2.0 ** -20) * (1.0 - codes / 65535.0)))
    if pos != raw_bytes or sum(len(m) for m in means) != total:
        sys.exit(f"plot_reflectivity_map: {path}: inconsistent payload")
    num = np.zeros(n)
    den = np.zeros(n)
    for j in range(SLOTS):
        cells = np.nonzero(k > j)[0]
        w = np.ones(len(cells))
        multi = k[cells] >= 2
        w[multi] = weights[j]
        num[cells] += w * means[j]
        den[cells] += w
    value = np.full(n, np.nan)
    value[den > 0] = num[den > 0] / den[den > 0]
    return tx, ty, value.reshape(size, size)  # row-major, y outer


class Layer:
    """A reflectivity layer as a dense mean-intensity raster over the tiles read."""

    def __init__(self, source, area=None):
        self.source = source
        if os.path.isdir(source):
            self._from_map(source, area)
        else:
            self._from_csv(source)

    def _from_map(self, map_dir, area):
        m = read_manifest(map_dir)
        res, size, (ox, oy) = m["resolution"], m["tile_size"], m["origin"]
        edge = size * res
        tiles = [t for t in m["tiles"] if area is None or (
            ox + t[0] * edge < area[1] and ox + (t[0] + 1) * edge > area[0] and
            oy + t[1] * edge < area[3] and oy + (t[1] + 1) * edge > area[2])]
        if not tiles:
            sys.exit(f"plot_reflectivity_map: {map_dir}: no tile in the area")
        x0, y0 = min(t[0] for t in tiles), min(t[1] for t in tiles)
        x1, y1 = max(t[0] for t in tiles), max(t[1] for t in tiles)
        self.img = np.full(((y1 - y0 + 1) * size, (x1 - x0 + 1) * size), np.nan)
        for tx, ty, name in tiles:
            _, _, v = tile_mean_intensity(os.path.join(map_dir, name), size)
            self.img[(ty - y0) * size:(ty - y0 + 1) * size, (tx - x0) * size:(tx - x0 + 1) * size] = v
        self.img /= m["metres_per_unit"]
        self.res, self.x0, self.y0 = res, ox + x0 * edge, oy + y0 * edge  # corner of img[0, 0]

    def _from_csv(self, csv):
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from plot_map_components import grid_of, load_cells

        cells = np.atleast_1d(load_cells(csv, None))
        ix, iy, shape, extent, res = grid_of(cells["x_m"], cells["y_m"])
        w = np.vstack([np.nan_to_num(cells[f"w{j}"]) for j in range(SLOTS)])
        w[0, cells["k"] == 1] = 1.0
        mu = np.vstack([np.nan_to_num(cells[f"mu{j}"]) for j in range(SLOTS)])
        self.img = np.full(shape, np.nan)
        self.img[iy, ix] = np.sum(w * mu, axis=0) / np.sum(w, axis=0) / 0.02  # build_map default
        self.res, self.x0, self.y0 = res, extent[0], extent[2]

    def window(self, x, y, nx, ny):
        """ny x nx cells whose first cell's corner is (x, y) (NaN outside the layer); the same
        resolution assumed."""
        i0 = int(round((x - self.x0) / self.res))
        j0 = int(round((y - self.y0) / self.res))
        out = np.full((ny, nx), np.nan)
        src = self.img[max(j0, 0):max(j0 + ny, 0), max(i0, 0):max(i0 + nx, 0)]
        out[max(-j0, 0):max(-j0, 0) + src.shape[0], max(-i0, 0):max(-i0, 0) + src.shape[1]] = src
        return out

    def crop(self, cx, cy, size):
        """The square [cx +- size/2] x [cy +- size/2] on this layer's grid, and its extent."""
        n = int(round(size / self.res))
        x = self.x0 + np.floor((cx - size / 2 - self.x0) / self.res) * self.res
        y = self.y0 + np.floor((cy - size / 2 - self.y0) / self.res) * self.res
        return self.window(x, y, n, n), (x, x + n * self.res, y, y + n * self.res)


def auto_center(layers, size, paint):
    """The window centre with the most paint cells of the first layer where every layer has data."""
    first = layers[0]
    ny, nx = first.img.shape
    covered = np.isfinite(first.img)
    for other in layers[1:]:
        if abs(other.res - first.res) > 1e-9:
            sys.exit("plot_reflectivity_map: --center auto needs maps of the same resolution")
        covered &= np.isfinite(other.window(first.x0, first.y0, nx, ny))
    score = (covered & (np.nan_to_num(first.img) >= paint)).astype(np.float64)
    n = int(round(size / first.res))
    c = np.pad(score, ((1, 0), (1, 0))).cumsum(0).cumsum(1)  # box sums by integral image
    if c.shape[0] <= n or c.shape[1] <= n:
        sys.exit("plot_reflectivity_map: the area is larger than the map")
    box = c[n:, n:] - c[:-n, n:] - c[n:, :-n] + c[:-n, :-n]
    j, i = np.unravel_index(np.argmax(box), box.shape)
    return first.x0 + (i + n / 2) * first.res, first.y0 + (j + n / 2) * first.res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("maps", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--center", default="auto", help="X,Y [m] or auto")
    ap.add_argument("--size", type=float, default=40.0, help="edge of the square area [m]")
    ap.add_argument("--labels", help="one label per map, comma-separated")
    ap.add_argument("--title", default="")
    ap.add_argument("--vmax", type=float, default=120.0, help="intensity drawn white")
    ap.add_argument("--paint", type=float, default=60.0, help="--center auto: paint intensity")
    ap.add_argument("--scale-bar", type=float, default=10.0, help="scale bar length [m]")
    ap.add_argument("--dpi", type=int, default=110)
    a = ap.parse_args()
    labels = a.labels.split(",") if a.labels else [os.path.basename(os.path.normpath(m)) for m in a.maps]
    if len(labels) != len(a.maps):
        sys.exit("plot_reflectivity_map: give one label per map")
    if a.center == "auto":
        layers = [Layer(m) for m in a.maps]
        cx, cy = auto_center(layers, a.size, a.paint)
    else:
        cx, cy = (float(v) for v in a.center.split(","))
        area = (cx - a.size / 2, cx + a.size / 2, cy - a.size / 2, cy + a.size / 2)
        layers = [Layer(m, area) for m in a.maps]

    cmap = LinearSegmentedColormap.from_list("grey", ["#000000", "#ffffff"])
    cmap.set_bad(NO_DATA)
    n = len(layers)
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n + 0.9, 5.3), squeeze=False)
    im = None
    for ax, layer, label in zip(axes[0], layers, labels):
        img, ext = layer.crop(cx, cy, a.size)
        data = np.isfinite(img)
        bright = np.sum(img[data] >= a.paint)
        im = ax.imshow(img, origin="lower", extent=ext, cmap=cmap, vmin=0, vmax=a.vmax,
                       interpolation="nearest")
        med = np.median(img[data]) if data.any() else float("nan")
        ax.set_title(f"{label}\nintensity: median {med:.0f}, {100.0 * bright / max(1, data.sum()):.1f}% "
                     f">= {a.paint:g}", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
        bx, by = ext[0] + 0.05 * a.size, ext[2] + 0.05 * a.size
        ax.plot([bx, bx + a.scale_bar], [by, by], color="#ffd21e", lw=3, solid_capstyle="butt")
        ax.text(bx + a.scale_bar / 2, by + 0.02 * a.size, f"{a.scale_bar:g} m", color="#ffd21e",
                ha="center", va="bottom", fontsize=9, weight="bold")
        print(f"{label}: {layer.source}: {data.sum()} of {img.size} cells with data, "
              f"{bright} >= {a.paint:g}, median {med:.1f}")
    fig.colorbar(im, ax=list(axes[0]), fraction=0.025, pad=0.02,
                 label="mean intensity of the ground returns (dark blue: none)")
    area = f"{a.size:g} m x {a.size:g} m around ({cx:.1f}, {cy:.1f}) m, {layers[0].res:g} m cells, north up"
    fig.suptitle(f"{a.title}\n{area}" if a.title else area, fontsize=10)
    fig.savefig(a.out, dpi=a.dpi)
    plt.close(fig)
    print(f"wrote {a.out} (centre {cx:.1f},{cy:.1f})")


if __name__ == "__main__":
    main()
