#!/usr/bin/env python3
"""Per-segment tracking plots of a pmg_policy_sil run (issue 12: "the robot goes where it is told").

Reads <out>/summary.json ("segments": command / reference / achieved per segment, means over the
last 60 % of each segment and over seeds) and <out>/seed<k>.csv (per tick), writes into <out>:

  segments_time.png      commanded vs reference vs achieved over time, one panel per axis
                         (vx, vy [m/s], wz [rad/s], torso pitch, roll [rad], pelvis height [m]) for
                         one seed; the averaging windows are shaded and their means drawn as bars;
                         dashed: the shaper's velocity command (vx_shaped, ... when the CSV has it:
                         the command after the controller's limits and envelopes).
                         The reference's vx/vy/wz are the base motion its stance feet imply
                         (pmg::gco::stanceImpliedVelocity), smoothed over --smooth seconds.
  segments_envelope.png  the tracking envelope: per segment, achieved/commanded (and the
                         reference's ratio beside it, and the shaper's command / commanded as a
                         dashed line when the summary has `shaped`) for every velocity axis the
                         segment commands,
                         and achieved - commanded for every posture axis it commands away from
                         neutral, against the issue's band (+-15 % or +-0.05 m/s / +-0.08 rad/s;
                         pitch/roll +-0.03 rad, height +-0.015 m); the posture panels also show
                         the other posture segments (marked *: cross-coupling, +-0.05 rad).

  python3 scripts/plot_segments.py OUT [--seed 0] [--smooth 0.5] [--title TEXT] [--envelope-png PATH]
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

AXES = ["vx", "vy", "wz", "pitch", "roll", "height"]
LABELS = {"vx": "v_x [m/s]", "vy": "v_y [m/s]", "wz": "yaw rate [rad/s]", "pitch": "torso pitch [rad]",
          "roll": "torso roll [rad]", "height": "pelvis height [m]"}
# Issue 12 targets: velocity within +-15 % or this absolute band when smaller; posture absolute.
VEL_REL, VEL_ABS = 0.15, {"vx": 0.05, "vy": 0.05, "wz": 0.08}
POSTURE_ABS = {"pitch": 0.03, "roll": 0.03, "height": 0.015}
COUPLING_ABS = 0.05  # torso pitch/roll on an axis not commanded (e.g. pitch in a squat) [rad]
MIN_COMMAND = 0.05  # velocity commands below this [m/s, rad/s] have no ratio (as pmg_policy_sil)

C_CMD, C_REF, C_ACH = "k", "tab:orange", "tab:blue"


def load_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no rows")
    cols = {}
    for k in rows[0]:
        if k in ("segment", "mode"):
            cols[k] = np.array([r[k] for r in rows])
        else:
            cols[k] = np.array([float(r[k]) if r[k] not in ("", "nan", "-nan") else math.nan for r in rows])
    return cols


def nan_smooth(x, n):
    """Centred moving mean over n samples, ignoring NaN (NaN where the window has no sample)."""
    if n <= 1:
        return x
    ok = np.isfinite(x)
    k = np.ones(n)
    s = np.convolve(np.where(ok, x, 0.0), k, mode="same")
    c = np.convolve(ok.astype(float), k, mode="same")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(c > 0, s / np.maximum(c, 1), math.nan)


def val(x):
    return math.nan if x is None else float(x)


def split_episodes(d):
    """With --restart-after-fall the CSV holds several episodes whose times overlap: a NaN row
    between them keeps the lines apart."""
    ep = d.get("episode")
    if ep is None or len(ep) < 2:
        return d
    cut = np.flatnonzero(np.diff(ep) != 0) + 1
    return {k: np.insert(x, cut, "" if x.dtype.kind in "US" else math.nan) for k, x in d.items()}


def plot_time(summary, d, seed, smooth, title, path):
    d = split_episodes(d)
    t = d["t"]
    dt = float(np.nanmedian(np.diff(t))) if len(t) > 1 else 0.01
    n = max(1, int(round(smooth / dt)))
    fig, axes = plt.subplots(len(AXES), 1, figsize=(max(12, summary["duration_s"] / 8), 13), sharex=True)
    active = d["mode"] == "active" if "mode" in d else np.ones(len(t), bool)  # the reference exists while active
    for ax, a in zip(axes, AXES):
        ref = d["height_ref"] if a == "height" else d.get(a + "_ref")
        if ref is not None:
            ref = np.where(active, ref, math.nan)
        ax.plot(t, d[a + "_cmd"], color=C_CMD, lw=1.0, label="command u")
        if a + "_shaped" in d:
            ax.plot(t, d[a + "_shaped"], color=C_CMD, lw=0.8, ls="--", alpha=0.6, label="shaped command")
        if ref is not None:
            r = nan_smooth(ref, n) if a in ("vx", "vy", "wz") else ref
            ax.plot(t, r, color=C_REF, lw=0.9, alpha=0.9,
                    label=f"reference (stance-implied, {smooth:g} s mean)" if a in ("vx", "vy", "wz") else "reference")
        ax.plot(t, nan_smooth(d[a], n) if a in ("vx", "vy", "wz") else d[a], color=C_ACH, lw=0.9,
                label=f"achieved ({smooth:g} s mean)" if a in ("vx", "vy", "wz") else "achieved")
        for s in summary.get("segments", []):
            w0, w1 = s["window"]
            ax.axvspan(w0, w1, color="0.9", lw=0)
            if s["seeds"] > 0:
                ax.hlines(val(s["reference"][a]), w0, w1, color=C_REF, lw=3, alpha=0.7)
                ax.hlines(val(s["achieved"][a]), w0, w1, color=C_ACH, lw=3, alpha=0.7)
        ax.set_ylabel(LABELS[a], fontsize=8)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
    top = axes[0]
    for s in summary.get("segments", []):
        top.text(0.5 * (s["t_begin"] + s["t_end"]), 1.02, s["name"], transform=top.get_xaxis_transform(),
                 rotation=90, fontsize=6, ha="center", va="bottom")
    axes[0].legend(fontsize=7, loc="upper right", ncol=3)
    axes[-1].set_xlabel("time [s]   (grey: averaging windows, last 60 % of each segment; "
                        "thick bars: their means over seeds)", fontsize=8)
    fig.suptitle(f"{title}  seed {seed}", fontsize=10, y=0.995)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def neutral_height(segments):
    hs = [round(val(s["command"]["height"]), 3) for s in segments]
    return max(set(hs), key=hs.count) if hs else 0.78


def plot_envelope(summary, title, path):
    segs = [s for s in summary.get("segments", [])]
    h0 = neutral_height(segs)
    nmax = max((s["seeds"] for s in segs), default=0)

    def label(s, suffix=""):  # the segment, with its seed count when some seeds fell
        return s["name"] + suffix + ("" if s["seeds"] == nmax else f" ({s['seeds']}/{nmax})")
    fig, axes = plt.subplots(2, 3, figsize=(18, 9))
    for ax, a in zip(axes.flat, AXES):
        names, ach, ref, lo, hi, shaped = [], [], [], [], [], []
        for s in segs:
            c = val(s["command"][a])
            if a in VEL_ABS:
                if abs(c) < MIN_COMMAND:
                    continue
                tol = max(VEL_REL, VEL_ABS[a] / abs(c))
                names.append(label(s))
                ach.append(val(s["ratio"][a]))
                ref.append(val(s["reference_ratio"][a]))
                shaped.append(val((s.get("shaped") or {}).get(a)) / c)
                lo.append(1 - tol)
                hi.append(1 + tol)
            else:
                # every segment that commands a posture: on its own axis the target band, on the
                # others the cross-coupling bound (marked *)
                dev = {p: abs(val(s["command"][p]) - (h0 if p == "height" else 0.0)) > 1e-6 for p in POSTURE_ABS}
                if not any(dev.values()):
                    continue
                names.append(label(s, "" if dev[a] else " *"))
                ach.append(val(s["achieved"][a]) - c)
                ref.append(val(s["reference"][a]) - c)
                band = POSTURE_ABS[a] if dev[a] or a == "height" else COUPLING_ABS
                lo.append(-band)
                hi.append(band)
        x = np.arange(len(names))
        for i in range(len(names)):
            ax.add_patch(plt.Rectangle((i - 0.45, lo[i]), 0.9, hi[i] - lo[i], color="tab:green", alpha=0.15, lw=0))
        ax.bar(x - 0.2, ref, 0.4, color=C_REF, label="reference")
        ax.bar(x + 0.2, ach, 0.4, color=C_ACH, label="achieved")
        if any(math.isfinite(v) for v in shaped):
            ax.hlines(shaped, x - 0.45, x + 0.45, color=C_CMD, lw=1.2, linestyles="--", label="shaped command")
        for i in range(len(names)):
            if not math.isfinite(ach[i]):
                ax.text(i + 0.2, 0, "fell", rotation=90, fontsize=6, ha="center", va="bottom", color="r")
        if a in VEL_ABS:
            ax.axhline(1.0, color="k", lw=0.8)
            ax.axhline(0.0, color="0.5", lw=0.5)
            ax.set_ylabel(f"{a}: measured / commanded", fontsize=8)
        else:
            ax.axhline(0.0, color="k", lw=0.8)
            unit = "m" if a == "height" else "rad"
            ax.set_ylabel(f"{a}: measured - commanded [{unit}]", fontsize=8)
        ax.set_xticks(x)
        ax.set_xticklabels(names, rotation=60, ha="right", fontsize=7)
        ax.tick_params(axis="y", labelsize=7)
        ax.grid(axis="y", alpha=0.3)
        ax.set_title(a, fontsize=9)
        if len(names) == 0:
            ax.text(0.5, 0.5, "not commanded", transform=ax.transAxes, ha="center")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="upper right")
    fig.suptitle(f"{title}\ntracking envelope per segment: steady state (last 60 % of each segment), mean over "
                 f"{nmax} seed(s) (n/{nmax}: seeds that did not fall); green: issue 12 target band; "
                 f"*: axis not commanded (cross-coupling)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="pmg_policy_sil --out directory")
    ap.add_argument("--seed", type=int, default=0, help="seed whose time series is plotted")
    ap.add_argument("--smooth", type=float, default=0.5, help="moving-mean window of the velocities [s]")
    ap.add_argument("--title", default=None)
    ap.add_argument("--envelope-png", default=None, help="also write the envelope plot here")
    a = ap.parse_args(argv)
    summary_path = os.path.join(a.out, "summary.json")
    try:
        with open(summary_path) as f:
            summary = json.load(f)
    except (OSError, ValueError) as e:
        raise SystemExit(f"{summary_path}: {e}")
    if "segments" not in summary:
        raise SystemExit(f"{summary_path}: no \"segments\" (written by an older pmg_policy_sil)")
    title = a.title or f"{os.path.basename(summary.get('model') or 'policy')} on " \
                       f"{os.path.basename(summary.get('commands', 'commands'))}"
    seed_csv = os.path.join(a.out, f"seed{a.seed}.csv")
    plot_time(summary, load_csv(seed_csv), a.seed, a.smooth, title, os.path.join(a.out, "segments_time.png"))
    env = os.path.join(a.out, "segments_envelope.png")
    plot_envelope(summary, title, env)
    if a.envelope_png:
        plot_envelope(summary, title, a.envelope_png)
    print("wrote", os.path.join(a.out, "segments_time.png"), env)
    return 0


if __name__ == "__main__":
    sys.exit(main())
