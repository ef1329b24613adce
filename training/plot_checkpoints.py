#!/usr/bin/env python3
"""When does a gait form? Per-segment results of a run's kept actors (train_pmg.py --keep-actors), one eval_mjx.py
rollout per checkpoint, against the training steps.

  python3 training/plot_checkpoints.py "N24a=/tmp/runs/N24a_actor_*.npz" "N24b=/tmp/runs/N24b_actor_*.npz" \\
      --segments back0.3_0.74 back0.5_0.74 back0.5_0.7 stop_back0.5_0.74 --warmup-steps 135e6 --out curve.png

Each file is an eval_mjx.py npz (segment_names, segment_command, segment_achieved: the means over the last 60 % of
each segment, NaN where the robot had fallen), or the text eval_mjx.py printed for it (.txt: its "per segment" table,
"fell" read as NaN; what a results folder keeps when the npz is left off), whose name holds the checkpoint's step as
actor_<digits> (--keep-actors' actors/actor_<step>.npz). One panel per segment: the achieved v_x [m/s, heading frame] of every run
against its steps [millions], the command, and the band issue 12 asks (±15 % or ±0.05 m/s); a fallen robot is
drawn as a cross on the panel's floor. Prints the same numbers as a table. --axis picks another of eval_mjx's
KEYS (vy, wz, pitch, roll, height). Errors: a file without a step in its name, a segment missing from a file.
"""
import argparse
import glob
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "scripts"))
from eval_mjx import KEYS  # noqa: E402  (the rollout's axes; JAX is imported only by its main)
import segment_band  # noqa: E402  (issue 12's velocity band, one definition: plot_segments.VEL_REL, VEL_ABS)


def checkpoint_step(path):
    """The training step of a kept actor's rollout, from actor_<digits> in its file name. Raises ValueError."""
    m = re.search(r"actor_(\d+)", os.path.basename(path))
    if not m:
        raise ValueError(f"{path}: no actor_<step> in the file name (train_pmg.py --keep-actors names them so)")
    return int(m.group(1))


def read_rollout(path):
    """(segment names, commanded [n, 6], achieved [n, 6]) of one eval_mjx.py rollout, columns in KEYS' order (m/s,
    rad/s, rad, m). An .npz is read as written; any other file as eval_mjx.py's printed output, whose table after the
    line "per segment (means ..." has per segment its name, then commanded and achieved per axis ("fell" where the
    robot was down: NaN), then the reward (and, for several robots, the count that fell). Raises ValueError naming the
    file when the text has no such table."""
    if path.endswith(".npz"):
        d = np.load(path)
        return [str(n) for n in d["segment_names"]], np.asarray(d["segment_command"]), np.asarray(d["segment_achieved"])
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    start = next((i for i, l in enumerate(lines) if l.startswith("per segment (means")), None)
    if start is None or start + 1 >= len(lines) or not lines[start + 1].split()[:1] == ["segment"]:
        raise ValueError(f"{path}: no eval_mjx.py 'per segment (means ...' table followed by its 'segment' header")
    names, command, achieved = [], [], []
    width = 1 + 2 * len(KEYS) + 1
    for line in lines[start + 2:]:
        tok = line.split()
        if len(tok) not in (width, width + 1):
            break
        try:
            pairs = [(float(tok[1 + 2 * k]), float("nan") if tok[2 + 2 * k] == "fell" else float(tok[2 + 2 * k]))
                     for k in range(len(KEYS))]
        except ValueError:
            break
        names.append(tok[0])
        command.append([c for c, _ in pairs])
        achieved.append([a for _, a in pairs])
    if not names:
        raise ValueError(f"{path}: the 'per segment' table has no rows of {width} columns")
    return names, np.array(command), np.array(achieved)


def load_run(pattern, segments, axis):
    """[(step, {segment: (commanded, achieved or nan)})] sorted by step, for the files matching pattern."""
    files = sorted(glob.glob(pattern))
    if not files:
        raise ValueError(f"{pattern}: no file matches")
    k = KEYS.index(axis)
    out = []
    for f in files:
        names, command, achieved = read_rollout(f)
        row = {}
        for s in segments:
            if s not in names:
                raise ValueError(f"{f}: no segment {s!r} (it has {', '.join(names)})")
            i = names.index(s)
            row[s] = (float(command[i][k]), float(achieved[i][k]))
        out.append((checkpoint_step(f), row))
    return sorted(out, key=lambda r: r[0])


def in_band(commanded, achieved, axis):
    """Issue 12's velocity band (segment_band.in_band); a fallen robot (NaN) is never in it."""
    return bool(np.isfinite(achieved) and segment_band.in_band(commanded, achieved, segment_band.VEL_ABS.get(axis, 0.0)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", metavar="LABEL=GLOB", help="a run's label and its rollouts' files")
    ap.add_argument("--segments", nargs="+", required=True, help="segment names of the rollouts' schedule")
    ap.add_argument("--axis", choices=KEYS, default="vx")
    ap.add_argument("--warmup-steps", type=float, default=None, help="the warm-up's end, drawn as a line [steps]")
    ap.add_argument("--out", default=None, help="PNG (default: the table alone)")
    a = ap.parse_args(argv)
    runs = []
    for spec in a.runs:
        label, sep, pattern = spec.partition("=")
        if not sep or not label or not pattern:
            ap.error(f"{spec!r}: expected LABEL=GLOB")
        try:
            runs.append((label, load_run(pattern, a.segments, a.axis)))
        except (ValueError, KeyError, OSError) as e:
            sys.exit(f"plot_checkpoints: {e}")
    print(f"{a.axis} achieved per checkpoint (commanded in the header; * in issue 12's band, 'fell': robot down)")
    print(f"{'run':8s} {'steps [M]':>9s} " + " ".join(f"{s[:17]:>17s}" for s in a.segments))
    for label, rows in runs:
        for step, row in rows:
            cells = [("fell" if not np.isfinite(v) else f"{v:+.3f}{'*' if in_band(c, v, a.axis) else ' '}")
                     + f" ({c:+.2f})" for c, v in (row[s] for s in a.segments)]
            print(f"{label:8s} {step / 1e6:9.1f} " + " ".join(f"{x:>17s}" for x in cells))
    if not a.out:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(a.segments), figsize=(4.0 * len(a.segments), 3.6), squeeze=False)
    for ax, s in zip(axes[0], a.segments):
        c = runs[0][1][0][1][s][0]
        tol = max(segment_band.VEL_REL * abs(c), segment_band.VEL_ABS.get(a.axis, 0.0))
        ax.axhspan(c - tol, c + tol, color="tab:green", alpha=0.15, label="issue 12's band")
        ax.axhline(c, color="tab:green", lw=1)
        values = [v for _, rows in runs for _, row in rows for v in [row[s][1]] if np.isfinite(v)]
        floor = min(values + [c - tol]) - 0.1
        for label, rows in runs:
            x = np.array([st / 1e6 for st, _ in rows])
            y = np.array([row[s][1] for _, row in rows])
            line, = ax.plot(x, y, "o-", ms=3, label=label)
            fell = ~np.isfinite(y)
            ax.plot(x[fell], np.full(fell.sum(), floor), "x", color=line.get_color(), ms=7)
        if a.warmup_steps:
            ax.axvline(a.warmup_steps / 1e6, color="0.5", ls="--", lw=1, label="warm-up ends")
        ax.set_title(f"{s} (commanded {c:+.2f})", fontsize=9)
        ax.set_xlabel("training steps [M]")
        ax.set_ylabel(f"achieved {a.axis} [{'rad/s' if a.axis == 'wz' else 'rad' if a.axis in ('pitch', 'roll') else 'm' if a.axis == 'height' else 'm/s'}]")
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.suptitle("each kept actor rolled out in MJX (nominal robot); a cross: the robot fell", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
