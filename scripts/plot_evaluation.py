#!/usr/bin/python3
"""Figures and Table I of the paper's section V from `evaluate` output directories.

    scripts/plot_evaluation.py --out FIG_DIR EVAL_DIR [EVAL_DIR ...]

Each EVAL_DIR is an `evaluate` output (summary.json, ekf.csv, matches.csv, offsets.csv,
traversal.ppm/.json). Writes into FIG_DIR:
  fig8_registration.png   Fig. 8: histogram of the registration error from random offsets (top)
                          and error against the initial offset (bottom), one column per dataset
                          (the height method's runs when there are any: the paper's figure;
                          the other methods' shares are in table1.md)
  fig9_traversal.png      Fig. 9: one branch-and-bound traversal (layers by heading slice)
  fig10_errors.png        Fig. 10: longitudinal and lateral error of the EKF over time (and the
                          raw matches), one row per run (the height method's when there are any)
  fig10_methods_<dataset>.png  Fig. 10 with the methods overlaid: when runs of one dataset,
                          world and mode used different methods (--method height, reflectivity,
                          fused; with --gps dashed) on the same drive, their EKF errors over time
                          in one plot (a run that never localized is listed as such)
  table1.md               Table I with the paper's numbers side by side
Uses Debian's python3-matplotlib and python3-numpy only (run with /usr/bin/python3).
"""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

PAPER = {  # Table I of the paper [m]
    "reflectivity": {"downtown": (0.124, 0.080), "snowy": (0.734, 0.629)},
    "proposed": {"downtown": (0.155, 0.103), "snowy": (0.180, 0.094)},
}
TARGET = {"downtown": (0.075, 0.05), "snowy": (0.09, 0.06)}  # the accuracy targets
SUCCESS_M = 0.5


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def column(rows, key, cast=float):
    return np.array([cast(r[key]) for r in rows], dtype=float)


def method_of(summary):
    """The run's method as Table I names it: "height", "reflectivity", "fused", with " with GPS"
    when evaluate ran with --gps."""
    return summary.get("method", "height") + (" with GPS" if summary.get("gps") else "")


def method_phrase(method):
    """"reflectivity with GPS" -> "reflectivity method with GPS" (labels and Table I rows)."""
    base = method.replace(" with GPS", "")
    return "%s method%s" % (base, " with GPS" if base != method else "")


def paper_figure_runs(runs):
    """The runs the paper's own figures show: the height method's, when there are any."""
    height = [r for r in runs if method_of(r["summary"]) == "height"]
    return height or runs


def load(directory):
    with open(os.path.join(directory, "summary.json")) as f:
        summary = json.load(f)
    return {
        "dir": directory,
        "summary": summary,
        "label": "%s (%s%s%s)" % (
            summary["dataset"], "replay" if summary["mode"] == "recorded" else "offline",
            ", %s world" % summary["world"] if summary.get("world") else "",
            ", " + method_phrase(method_of(summary)) if method_of(summary) != "height" else ""),
        "ekf": read_csv(os.path.join(directory, "ekf.csv")),
        "matches": read_csv(os.path.join(directory, "matches.csv")),
        "offsets": read_csv(os.path.join(directory, "offsets.csv")),
    }


def fig8(runs, path):
    runs = [r for r in runs if r["offsets"]]
    if not runs:
        return None
    fig, axes = plt.subplots(2, len(runs), figsize=(5.0 * len(runs), 7.0), squeeze=False)
    for k, run in enumerate(runs):
        off = run["offsets"]
        has = column(off, "has_result") > 0
        err = np.where(has, column(off, "error_m"), np.inf)
        init = column(off, "offset_m")
        finite = err[np.isfinite(err)]
        ok = np.mean(err <= SUCCESS_M) if len(err) else float("nan")
        top = axes[0][k]
        # The x range follows the data (the paper's errors spread to ~0.5 m; these may not).
        hi = min(1.0, max(0.15, 1.2 * float(np.max(finite)) if len(finite) else 1.0))
        top.hist(np.clip(finite, 0, hi), bins=np.linspace(0, hi, 31), color="tab:blue",
                 edgecolor="white")
        if hi >= SUCCESS_M:
            top.axvline(SUCCESS_M, color="tab:red", linestyle="--", label="0.5 m")
        failed = int(np.sum(~(err <= SUCCESS_M)))
        top.plot([], [], " ", label="%d beyond 0.5 m or no result" % failed)
        top.set_xlim(0, hi)
        top.set_xlabel("registration error, L2 [m]%s" % (" (clipped at 1 m)" if hi >= 1.0 else ""))
        top.set_ylabel("registrations")
        top.set_title("%s: %d of %d within 0.5 m (%.1f%%)" % (
            run["summary"]["dataset"], int(np.sum(err <= SUCCESS_M)), len(err), 100 * ok))
        top.legend()
        bottom = axes[1][k]
        good = err <= SUCCESS_M
        bottom.scatter(init[good], err[good], s=10, color="tab:blue", label="within 0.5 m")
        bad = ~good
        if np.any(bad):
            shown = np.where(np.isfinite(err[bad]), err[bad], 5.0)
            bottom.scatter(init[bad], np.minimum(shown, 5.0), s=18, color="tab:red", marker="x",
                           label="failed (no result: 5 m)")
        bottom.set_xlim(0, max(10.0, float(np.max(init)) if len(init) else 10.0))
        bottom.set_yscale("log")
        bottom.set_ylim(1e-3, 10)
        bottom.set_xlabel("initial offset [m]")
        bottom.set_ylabel("registration error [m]")
        bottom.grid(True, which="both", alpha=0.3)
        bottom.legend(loc="upper left")
    fig.suptitle("Fig. 8: registration from random offsets\n(within 10 m, +-15 deg; "
                 "window 25 m x 25 m x +-15 deg)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def read_ppm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(maxsplit=4)  # P6, width, height, maxval, pixels
    if parts[0] != b"P6":
        raise ValueError("%s is not a binary PPM" % path)
    w, h = int(parts[1]), int(parts[2])
    pixels = parts[4]
    return np.frombuffer(pixels[: w * h * 3], dtype=np.uint8).reshape(h, w, 3)


def fig9(runs, path):
    for run in runs:
        ppm = os.path.join(run["dir"], "traversal.ppm")
        meta_path = os.path.join(run["dir"], "traversal.json")
        if not (os.path.exists(ppm) and os.path.exists(meta_path)):
            continue
        with open(meta_path) as f:
            meta = json.load(f)
        img = read_ppm(ppm)
        fig, ax = plt.subplots(figsize=(14, 14 * img.shape[0] / img.shape[1] + 1.2))
        ax.imshow(img, interpolation="nearest")
        tw, th, gap = meta["tile_width"], meta["tile_height"], meta["gap"]
        cols, layers = meta["columns"], meta["layers"]
        step = meta["heading_step_offset"]
        deg = math.degrees(meta["heading_step_rad"])
        ax.set_xticks([c * (tw + gap) + tw / 2 for c in range(cols)])
        ax.set_xticklabels(["h*%+d\n(%+.1f deg)" % ((c - cols // 2) * step, (c - cols // 2) * step * deg)
                            if c != cols // 2 else "h*\n(optimum)" for c in range(cols)], fontsize=8)
        ax.set_yticks([r * (th + gap) + th / 2 for r in range(layers)])
        ax.set_yticklabels(["Multires-%d" % (layers - 1 - r) if r < layers - 1 else "Base GMM"
                            for r in range(layers)])
        frac = meta["evaluations"] / max(1, meta["exhaustive_poses"])
        ax.set_title("Fig. 9: branch-and-bound traversal of one %.0f m x %.0f m search (%s), a heading slice every "
                     "%d steps around the optimum h*\n%d node scores = %.2f%% of the "
                     "%d exhaustive poses, search %.0f ms; colour = bound (blue low, yellow high), "
                     "black = never scored, white cross = optimum"
                     % (2 * meta["half_x_m"], 2 * meta["half_x_m"], run["summary"]["dataset"], step,
                        meta["evaluations"], 100 * frac, meta["exhaustive_poses"],
                        meta["search_ms"]), fontsize=10)
        fig.tight_layout()
        fig.savefig(path, dpi=100)
        plt.close(fig)
        return path
    return None


def fig10(runs, path):
    runs = [r for r in runs if r["ekf"]]
    if not runs:
        return None
    # One row per run (like the paper's (a) Downtown, (b) Snowy), longitudinal and lateral.
    fig, axes = plt.subplots(len(runs), 2, figsize=(13.0, 2.8 * len(runs) + 0.6), squeeze=False,
                             sharex=True)
    # A common y range from the bulk of the errors; a few samples beyond it (e.g. a start-up
    # transient) are drawn on the border and counted in the legend.
    bulk = np.concatenate([np.abs(column(r["ekf"], k)) for r in runs
                           for k in ("longitudinal_m", "lateral_m")])
    lim = max(0.15, 1.3 * float(np.percentile(bulk, 99.5)))
    for k, run in enumerate(runs):
        ekf = run["ekf"]
        t = column(ekf, "t")
        t0 = t[0]
        matches = [m for m in run["matches"] if m["outcome"] == "accepted" and m["has_pose"] == "1"]
        mt = column(matches, "stamp") - t0 if matches else np.array([])
        s = run["summary"]
        for col, (key, name) in enumerate([("longitudinal_m", "longitudinal"),
                                           ("lateral_m", "lateral")]):
            ax = axes[k][col]
            if matches:
                ax.scatter(mt, np.clip(column(matches, key), -lim, lim), s=3, color="tab:gray",
                           alpha=0.5, label="raw matches (RMS %s)" % cm(s["raw_matches"]["rms_" + key]))
            e = column(ekf, key)
            ax.plot(t - t0, np.clip(e, -lim, lim), color="tab:blue" if col == 0 else "tab:orange",
                    linewidth=1.0, label="EKF (RMS %s)" % cm(s["ekf"]["rms_" + key]))
            out = int(np.sum(np.abs(e) > lim))
            if out:
                ax.plot([], [], " ", label="%d EKF samples beyond +-%.2f m (max %.2f m)"
                        % (out, lim, float(np.max(np.abs(e)))))
            ax.axhline(0, color="black", linewidth=0.5)
            ax.set_ylim(-lim, lim)
            ax.set_ylabel("%s error [m]" % name)
            ax.set_title("%s: %s" % (run["label"], name), fontsize=10)
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle("Fig. 10: localization error relative to ground truth")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


METHOD_COLOURS = {"height": "tab:blue", "reflectivity": "tab:red", "fused": "tab:green"}


def fig10_methods(runs, out_dir):
    """One figure per (dataset, world, mode) run with several methods: their EKF errors
    overlaid (longitudinal and lateral), so the methods compare on the same drive."""
    groups = {}
    for r in runs:
        s = r["summary"]
        groups.setdefault((s["dataset"], s.get("world", ""), s["mode"]), []).append(r)
    made = []
    for (dataset, world, mode), group in sorted(groups.items()):
        methods = {method_of(r["summary"]) for r in group}
        if len(methods) < 2:
            continue
        group.sort(key=lambda r: (list(METHOD_COLOURS).index(r["summary"].get("method", "height"))
                                  if r["summary"].get("method", "height") in METHOD_COLOURS
                                  else 99, bool(r["summary"].get("gps"))))
        data = [r for r in group if r["ekf"]]
        bulk = np.concatenate([np.abs(column(r["ekf"], k)) for r in data
                               for k in ("longitudinal_m", "lateral_m")] or [np.zeros(1)])
        lim = max(0.1, 1.3 * float(np.percentile(bulk, 99.5)))
        fig, axes = plt.subplots(2, 1, figsize=(11.0, 6.2), sharex=True)
        t0 = min((column(r["ekf"], "t")[0] for r in data), default=0.0)
        for col, (key, name) in enumerate([("longitudinal_m", "longitudinal"),
                                           ("lateral_m", "lateral")]):
            ax = axes[col]
            for r in group:
                s = r["summary"]
                method = method_of(s)
                colour = METHOD_COLOURS.get(s.get("method", "height"), "tab:gray")
                style = "--" if s.get("gps") else "-"
                if not r["ekf"]:
                    ax.plot([], [], " ", label="%s: never localized, no EKF output (%s of %s "
                            "scans accepted)" % (method, s.get("accepted", "?"), s.get("scans", "?")))
                    continue
                t, e = column(r["ekf"], "t") - t0, column(r["ekf"], key)
                late = " (EKF from %.1f s)" % t[0] if t[0] > 0.5 else ""
                ax.plot(t, np.clip(e, -lim, lim), color=colour, linewidth=1.1, linestyle=style,
                        label="%s: EKF RMS %s, max |error| %s; %s of %s scans accepted%s" % (
                            method, cm(s["ekf"]["rms_" + key]), cm(float(np.max(np.abs(e)))),
                            s.get("accepted", "?"), s.get("scans", "?"), late))
                out = int(np.sum(np.abs(e) > lim))
                if out:
                    ax.plot([], [], " ", label="  %d samples beyond +-%.2f m (max %.2f m)"
                            % (out, lim, float(np.max(np.abs(e)))))
            ax.axhline(0, color="black", linewidth=0.5)
            ax.set_ylim(-lim, lim)
            ax.set_ylabel("%s error [m]" % name)
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8)
        axes[-1].set_xlabel("time [s]")
        fig.suptitle("Fig. 10 by method: EKF error relative to ground truth, %s drive (%s%s)" % (
            dataset, "replay" if mode == "recorded" else "offline",
            ", %s world" % world if world else ""))
        fig.tight_layout()
        path = os.path.join(out_dir, "fig10_methods_%s%s.png" % (
            dataset, "_%s" % world if world and world != "perfect" else ""))
        fig.savefig(path, dpi=100)
        plt.close(fig)
        made.append(path)
    return made


def integrity(runs, path):
    """Stanford-style plot: error against protection level of every registration with a
    certificate (drive matches and Fig. 8), certified in blue, uncertified in grey; points
    right of the diagonal or above the alert limit while certified would be misleading."""
    alert = 0.29
    series = []
    for run in runs:
        for kind, rows in (("drive", run["matches"]), ("Fig. 8", run["offsets"])):
            rows = [r for r in rows if r.get("protection_xy_m") not in (None, "")
                    and (kind == "Fig. 8" and r["has_result"] == "1"
                         or kind == "drive" and r["outcome"] == "accepted" and r["has_pose"] == "1")]
            if rows:
                series.append((run, kind, rows))
    if not series:
        return None
    fig, axes = plt.subplots(1, len(series), figsize=(4.6 * len(series), 4.4), squeeze=False)
    for k, (run, kind, rows) in enumerate(series):
        ax = axes[0][k]
        pl = column(rows, "protection_xy_m")
        if kind == "drive":
            err = np.hypot(column(rows, "longitudinal_m"), column(rows, "lateral_m"))
        else:
            err = column(rows, "error_m")
        cert = column(rows, "certified") > 0
        top = max(1.0, float(np.max(pl)) * 1.1, float(np.max(err)) * 1.1)
        ax.scatter(pl[~cert], err[~cert], s=8, color="tab:gray", label="uncertified (%d)" % int(np.sum(~cert)))
        ax.scatter(pl[cert], err[cert], s=8, color="tab:blue", label="certified (%d)" % int(np.sum(cert)))
        ax.plot([1e-3, top], [1e-3, top], color="black", linewidth=0.8, label="error = protection level")
        ax.axhline(alert, color="tab:red", linestyle="--", linewidth=0.8, label="alert limit 0.29 m")
        bad = int(np.sum(cert & ((err > pl) | (err > alert))))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(0.05, top)
        ax.set_ylim(1e-3, top)
        ax.set_xlabel("protection level [m]")
        ax.set_ylabel("error against ground truth [m]")
        ax.set_title("%s, %s: %d misleading" % (run["summary"]["dataset"], kind, bad))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper left", fontsize=7)
    fig.suptitle("Integrity: error against protection level")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def cm(v):
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else "%.1f cm" % (100 * v)


def table1(runs, path):
    datasets = ["downtown", "snowy"]
    header = ("| Method | Downtown longitudinal | Downtown lateral | Downtown Snowy longitudinal "
              "| Downtown Snowy lateral | scan matches |\n|---|---|---|---|---|---|\n")
    lines = [header]
    lines.append("| Paper: reflectivity (Levinson) | 12.4 cm | 8.0 cm | 73.4 cm* | 62.9 cm* | - |\n")
    lines.append("| Paper: proposed | 15.5 cm | 10.3 cm | 18.0 cm | 9.4 cm | 3-4 Hz |\n")
    worlds = []
    for r in runs:
        if r["summary"].get("world", "") not in worlds:
            worlds.append(r["summary"].get("world", ""))
    kinds = (("ekf", "EKF output"), ("raw_matches", "raw matches"),
             ("ekf_in_map_frame", "EKF against the truth in the map's frame"),
             ("raw_matches_in_map_frame", "raw matches against the truth in the map's frame"),
             ("map_error", "the map's own error (its poses against their truth)"))
    groups = [(w, m, mode) for w in worlds
              for m in ("height", "reflectivity", "reflectivity with GPS", "fused")
              for mode in ("bag", "recorded")]
    mode_names = {"bag": "offline (evaluate bag)", "recorded": "replay (rosbag play)"}
    for world, method, mode in groups:
        mode_name = mode_names[mode]
        by_ds = {r["summary"]["dataset"]: r["summary"] for r in runs
                 if r["summary"]["mode"] == mode and r["summary"].get("world", "") == world
                 and method_of(r["summary"]) == method}
        if not by_ds:
            continue
        name = "%s, %s world" % (mode_name, world) if world else mode_name
        for kind, kind_name in kinds:
            if not any(s.get(kind) for s in by_ds.values()):
                continue  # the map-frame rows only with evaluate --map-poses
            if kind == "map_error" and method != "height":
                continue  # the same map poses: printed once, with the height method
            cells = []
            for ds in datasets:
                s = by_ds.get(ds)
                for axis in ("rms_longitudinal_m", "rms_lateral_m"):
                    cell = cm(s[kind][axis]) if s and s.get(kind) else "-"
                    loc = s.get("ekf_localized") if s and kind == "ekf" else None
                    if (loc and loc["count"] and s[kind][axis] is not None
                            and abs(loc[axis] - s[kind][axis]) > 0.0005):
                        cell += " (%s+)" % cm(loc[axis])  # without not-yet-localized samples
                    elif loc is not None and not loc["count"] and s[kind][axis] is not None:
                        cell += " (never localized: sigma > 1 m throughout)"
                    cells.append(cell)
            rates = ", ".join("%s %.1f Hz (%.0f%% of scans)" % (ds, s["match_rate_hz"],
                                                               100 * s["accepted_share"])
                              for ds, s in by_ds.items())
            label = "This work" if kind != "map_error" else "Map"
            if method != "height" and kind != "map_error":
                label = "This work, " + method_phrase(method)
            lines.append("| %s, %s, %s | %s | %s |\n" % (
                label, name, kind_name, " | ".join(cells), rates if kind == "ekf" else "-"))
    lines.append("| Target | 7.5 cm | 5.0 cm | 9.0 cm | 6.0 cm | 10 Hz |\n")
    lines.append("\n*: with GPS (paper). +: over the EKF samples whose reported sigma is at most "
                 "1 m (the filter's start-up transient left out; \"never localized\": no such "
                 "sample, the filter's sigma stayed above 1 m). RMS over the evaluated drives; "
                 "the paper's drives are 3.0 km, see each run's summary.md for its length. "
                 "The imperfect world (docs/evaluation.md): a map built from SLAM-like poses, "
                 "map aging and calibration errors; \"in the map's frame\": against the truth "
                 "moved by the map's own error where the vehicle is.\n")
    for r in runs:
        s = r["summary"]
        o = s["offsets"]
        p = s["processing_ms"]
        ms = "%.0f/%.0f ms" % (p["p50"], p["p95"]) if p["p50"] is not None else "-"
        if s["mode"] == "recorded":
            lines.append("\n%s: %.1f s of driving replayed at real time; %d of %d scans matched "
                         "(%d dropped as stale); matching p50/p95 %s; latency p50/p95 %.0f/%.0f ms"
                         % (r["label"], s["duration_s"], s["accepted"], s["scans"],
                            s["dropped_scans"], ms, 1000 * (s["latency_s"]["p50"] or 0),
                            1000 * (s["latency_s"]["p95"] or 0)))
        else:
            lines.append("\n%s: %.1f s of driving evaluated in %.1f s wall (%.2fx real time); "
                         "matching p50/p95 %s" % (r["label"], s["duration_s"], s["wall_s"],
                                                  s["duration_s"] / s["wall_s"], ms))
        if o["trials"]:
            lines.append("; Fig. 8: %.1f%% of %d registrations from random 10 m offsets within 0.5 m"
                         % (100 * o["success_within_0_5m"], o["trials"]))
        if "obstacles" in s:
            a = s["obstacles"]["all"]
            lines.append("; obstacles precision %.1f%% recall %.1f%%" % (
                100 * (a["precision"] or 0), 100 * (a["recall"] or 0)))
        lines.append(".\n")
    with open(path, "w") as f:
        f.write("".join(lines))
    return path


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True, help="directory for the figures and table1.md")
    p.add_argument("dirs", nargs="+", help="evaluate output directories")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    runs = [load(d) for d in a.dirs]
    # Offline runs first, then replays; Downtown before Snowy.
    # Perfect (or unlabelled) world before the imperfect one.
    runs.sort(key=lambda r: (r["summary"]["mode"] != "bag",
                             r["summary"].get("world", "") not in ("", "perfect"),
                             r["summary"]["dataset"] != "downtown"))
    offline = [r for r in runs if r["summary"]["mode"] == "bag"] or runs
    made = [fig8(paper_figure_runs(offline), os.path.join(a.out, "fig8_registration.png")),
            fig9(offline, os.path.join(a.out, "fig9_traversal.png")),
            fig10(paper_figure_runs(runs), os.path.join(a.out, "fig10_errors.png")),
            integrity(offline, os.path.join(a.out, "integrity.png")),
            table1(runs, os.path.join(a.out, "table1.md"))]
    made += fig10_methods(runs, a.out)
    for m in made:
        if m:
            print("wrote %s" % m)
    return 0


if __name__ == "__main__":
    sys.exit(main())
