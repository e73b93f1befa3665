#!/usr/bin/python3
"""How the EKF's output stands against its own scan matches, from `evaluate` output directories.

    scripts/ekf_against_matches.py EVAL_DIR [EVAL_DIR ...]

Reads ekf.csv and matches.csv of each EVAL_DIR and prints one Markdown table row per directory:
the EKF's and the raw matches' longitudinal / lateral RMS against the truth, and the EKF's
longitudinal error minus its matches' (the matches' error interpolated to the EKF's samples):
its mean while moving (over 1 m/s) and while stopped (under 0.5 m/s), and a least-squares fit
of it as a constant plus terms in speed and acceleration (speed and acceleration from the
ground truth in ekf.csv). A positive difference means the EKF is ahead of its matches.
Then, over the first and the last WINDOW_S (20 s) of the drive: the EKF's INS twist scale s
(ekf.csv's twist_scale, mean; "-" in outputs without it) and the raw matches' longitudinal error
per distance driven (the slope of a line fitted to it against the distance, in percent): where
the map is stretched or compressed against the world, the matches imply a distance that differs
from the true one by that share, and the INS scale calibrated against them learns it.
docs/evaluation.md ("The EKF worse than its matches in the imperfect world") uses it.
A directory without EKF samples or without matches with a pose is reported as having no data;
the exit status is then 1. Uses Debian's python3-numpy only (run with /usr/bin/python3).
"""
import csv
import os
import sys

import numpy as np

MOVING_MPS = 1.0
STOPPED_MPS = 0.5
WINDOW_S = 20.0


def read_rows(path):
    """The rows of a CSV file as dicts keyed by its header."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def columns(rows, names):
    """The named columns of CSV rows as float arrays (empty cells are NaN)."""
    return {n: np.array([float(r[n]) if r[n] != "" else np.nan for r in rows]) for n in names}


def rms_cm(x):
    return 100.0 * float(np.sqrt(np.mean(np.square(x))))


def windows(t):
    """Masks of the first and the last WINDOW_S of the times t."""
    return [t <= t.min() + WINDOW_S, t >= t.max() - WINDOW_S]


def scale_cells(ekf_rows, t):
    """Mean twist scale [%] over the first and the last window, or '-' without the column."""
    if "twist_scale" not in ekf_rows[0]:
        return "-"
    s = columns(ekf_rows, ["twist_scale"])["twist_scale"]
    means = [np.nanmean(s[w]) if np.any(np.isfinite(s[w])) else np.nan for w in windows(t)]
    return " / ".join("-" if np.isnan(m) else f"{100 * m:+.2f} %" for m in means)


def stretch_cells(t, distance, m_t, m_long):
    """The matches' longitudinal error per distance driven [%] in the first and last window."""
    m_distance = np.interp(m_t, t, distance)
    out = []
    for w in windows(m_t):
        if np.count_nonzero(w) < 3 or np.ptp(m_distance[w]) < 1.0:
            out.append("-")
            continue
        slope = np.polyfit(m_distance[w], m_long[w], 1)[0]
        out.append(f"{100 * slope:+.2f} %")
    return " / ".join(out)


def row(directory):
    """One table row for an evaluate output directory, or None when it holds no data."""
    ekf_rows = read_rows(os.path.join(directory, "ekf.csv"))
    ekf = columns(ekf_rows, ["t", "gt_x", "gt_y", "longitudinal_m", "lateral_m"])
    matches = columns(read_rows(os.path.join(directory, "matches.csv")),
                      ["stamp", "has_pose", "longitudinal_m", "lateral_m"])
    with_pose = matches["has_pose"] == 1
    t = ekf["t"]
    if t.size < 3 or np.count_nonzero(with_pose) < 2:
        return None
    m_t = matches["stamp"][with_pose]
    m_long = matches["longitudinal_m"][with_pose]
    m_lat = matches["lateral_m"][with_pose]
    dt = np.maximum(np.diff(t), 1e-3)
    speed = np.hypot(np.diff(ekf["gt_x"]), np.diff(ekf["gt_y"])) / dt
    distance = np.concatenate([[0.0], np.cumsum(speed * dt)])
    speed = np.concatenate([[speed[0]], speed])
    accel = np.gradient(speed, t)
    # Only where matches exist on both sides: no extrapolation.
    inside = (t >= m_t.min()) & (t <= m_t.max())
    diff = ekf["longitudinal_m"][inside] - np.interp(t[inside], m_t, m_long)
    v, a = speed[inside], accel[inside]
    fit, *_ = np.linalg.lstsq(np.c_[np.ones_like(v), v, a], diff, rcond=None)
    moving, stopped = diff[v > MOVING_MPS], diff[v < STOPPED_MPS]

    def mean_cm(x):
        return f"{100.0 * x.mean():+.2f} cm" if x.size else "-"

    return (f"| {directory} | {rms_cm(ekf['longitudinal_m']):.1f} / {rms_cm(ekf['lateral_m']):.1f} cm"
            f" | {rms_cm(m_long):.1f} / {rms_cm(m_lat):.1f} cm | {mean_cm(moving)} | "
            f"{mean_cm(stopped)} | {100 * fit[0]:+.2f} cm, {100 * fit[1]:+.3f} cm per m/s, "
            f"{100 * fit[2]:+.2f} cm per m/s^2 | {scale_cells(ekf_rows, t)} | "
            f"{stretch_cells(t, distance, m_t, m_long)} |")


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) >= 2 else 2
    print("| run | EKF long. / lat. RMS | raw long. / lat. RMS | EKF - raw moving | "
          "EKF - raw stopped | EKF - raw fit: constant, speed, acceleration | "
          f"twist scale s, first / last {WINDOW_S:.0f} s | "
          f"raw long. error per distance, first / last {WINDOW_S:.0f} s |")
    print("|---|---|---|---|---|---|---|---|")
    status = 0
    for directory in argv[1:]:
        try:
            line = row(directory)
        except (OSError, KeyError, ValueError) as e:
            print(f"{directory}: cannot read: {e}", file=sys.stderr)
            status = 1
            continue
        if line is None:
            print(f"{directory}: no data (no EKF samples or fewer than two matches with a pose)",
                  file=sys.stderr)
            status = 1
            continue
        print(line)
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
