#!/usr/bin/env python3
"""Per robot and segment of an `eval_mjx.py --randomized N` rollout: the distribution behind its pooled means.

eval_mjx.py pools the robots of a randomized rollout into one mean per segment. Whether an actor runs away
for a few robots or for most of them is in the per-robot numbers; and the rollout's .npz (every tick of every
robot) is too large to bring back from the device machine for N = 128. Two steps:

  python3 training/segment_robots.py summarize ROLLOUT.npz --commands SCHEDULE.yaml --out ROBOTS.json
  python3 training/segment_robots.py report NAME=ROBOTS.json ... [--factor 1.5] [--plot FIG.png]

summarize: per segment of the schedule (eval_mjx.schedule) and per robot, over the last 60 % of the segment
(eval_mjx.py's and pmg_policy_sil's window): "vx" the mean forward velocity [m/s] (heading frame, the
environment's measured[0]) and "flight" the share of ticks with neither foot on the floor, both None where
the robot fell in or before the window; "fallen_by_end" whether it fell by the window's end; "command_vx"
the segment's commanded v_x [m/s]. Also the robots' drawn friction and total mass [kg].

report: one row per rollout: robots fallen by the end of the schedule, and per walking segment (|command
v_x| >= 0.05 m/s) the median achieved v_x of the robots standing through it, the share of them running
away (achieved beyond --factor times the command, in its direction) and the median flight share; then the
robots that fell in each segment (those standing at the end of the previous segment's window and fallen by
the end of this one's; every segment, walking or not). --plot draws achieved over commanded v_x per robot,
one panel per walking segment; --plot-falls draws the falls per segment, one bar per rollout.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from eval_mjx import schedule, segment_window  # noqa: E402


def summarize(npz, commands):
    """The per-robot summary (module docstring) of the rollout @p npz run on the schedule file @p commands.
    Raises ValueError when the rollout and the schedule do not match (a tick beyond the schedule's end)."""
    z = np.load(npz)
    t, meas = z["t"], z["measured"]  # (ticks,), (robots, ticks, 8): v_H (3), height, contacts (2), pitch, roll
    if meas.ndim != 3 or meas.shape[1] != t.shape[0]:
        raise ValueError(f"{npz}: 'measured' has shape {meas.shape}, expected (robots, {t.shape[0]}, 8)")
    at, duration, spans = schedule(commands)
    if t[-1] >= duration + 1e-9:
        raise ValueError(f"{npz}: the rollout runs to {t[-1]:.2f} s, beyond {commands}'s {duration} s")
    alive = np.cumsum(z["done"] > 0, axis=1) == 0
    out = {}
    for name, t0, t1 in spans:
        window = segment_window(t, t0, t1)
        vx, flight, fallen = [], [], []
        for r in range(meas.shape[0]):
            standing = window & alive[r]
            fallen.append(bool(window.any() and not alive[r][window].all()))
            if not window.any() or standing.sum() < window.sum():
                vx.append(None)
                flight.append(None)
                continue
            vx.append(round(float(meas[r, standing, 0].mean()), 4))
            flight.append(round(float(np.mean(~(meas[r, standing, 4:6] > 0.5).any(axis=1))), 4))
        out[name] = {"command_vx": float(at(t0 + 0.5 * (t1 - t0))[0]), "vx": vx, "flight": flight,
                     "fallen_by_end": fallen}
    for key, digits in (("drawn_friction", 4), ("drawn_mass", 3)):
        out[key] = np.round(np.asarray(z[key], np.float64), digits).tolist() if key in z.files else []
    return out


def segments(summary):
    """The segment entries of a summary, in schedule order (the robots' draws left out)."""
    return [(k, v) for k, v in summary.items() if isinstance(v, dict)]


def rows(summary, factor):
    """(robots fallen by the end, [(segment, command v_x, median v_x, running-away share, median flight,
    robots standing)] for the walking segments) of one summary."""
    segs = segments(summary)
    fallen = sum(segs[-1][1]["fallen_by_end"]) if segs else 0
    out = []
    for name, s in segs:
        c = s["command_vx"]
        if abs(c) < 0.05:
            continue
        v = np.array([x for x in s["vx"] if x is not None], float)
        f = np.array([x for x in s["flight"] if x is not None], float)
        if v.size == 0:
            out.append((name, c, float("nan"), float("nan"), float("nan"), 0))
            continue
        out.append((name, c, float(np.median(v)), float(np.mean(v * np.sign(c) > factor * abs(c))),
                    float(np.median(f)), int(v.size)))
    return fallen, out


def fell_in(summary):
    """[(segment, robots that fell in it)] in schedule order: fallen by the end of this segment's window and
    not by the end of the previous one's (segment_robots.py's fallen_by_end)."""
    out, before = [], None
    for name, s in segments(summary):
        now = s["fallen_by_end"]
        out.append((name, sum(bool(f) and not (before is not None and before[i]) for i, f in enumerate(now))))
        before = now
    return out


def _pyplot():
    """matplotlib.pyplot on the file-only Agg backend (the scripts run headless)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot_falls(named, path):
    """Grouped bars: per segment of the first rollout's schedule, the robots of each rollout that fell in it."""
    falls = [(name, fell_in(summary), len(segments(summary)[0][1]["fallen_by_end"])) for name, summary in named]
    names = [seg for seg, _ in falls[0][1]]
    for name, per_segment, _ in falls:
        if [seg for seg, _ in per_segment] != names:
            raise ValueError(f"{name}: its segments differ from {named[0][0]}'s: not the same schedule")
    plt = _pyplot()
    width = 0.8 / len(named)
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(names)) + 2.2, 3.8))
    for i, (name, per_segment, n) in enumerate(falls):
        counts = [k for _, k in per_segment]
        ax.bar(np.arange(len(names)) + (i - (len(named) - 1) / 2) * width, counts, width,
               label=f"{name}: {sum(counts)} of {n} fell")
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels(names, rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("robots that fell in the segment")
    ax.legend(fontsize=8, bbox_to_anchor=(1.01, 1.0), loc="upper left")
    ax.set_title("eval_mjx --randomized: where the robots fall", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def report(named, factor, plot=None, falls_plot=None):
    """Prints the table (module docstring) of @p named [(name, summary)]; draws --plot and --plot-falls when
    given (ValueError when --plot-falls gets rollouts of different schedules, or --plot a schedule without a
    walking segment)."""
    print(f"robots fallen by the end; per walking segment: median achieved v_x [m/s] / share beyond {factor} x "
          f"the command / median flight share (robots standing through it)")
    for name, summary in named:
        fallen, segs = rows(summary, factor)
        n = len(segments(summary)[0][1]["vx"]) if segments(summary) else 0
        cells = [f"{s} no robot standing (0)" if k == 0 else f"{s} {m:+.2f} / {100 * r:.0f} % / {fl:.2f} ({k})"
                 for s, _, m, r, fl, k in segs]
        print(f"{name:6s} fallen {fallen:3d}/{n}  " + "  ".join(cells))
    for name, summary in named:
        where = [f"{seg} {k}" for seg, k in fell_in(summary) if k]
        print(f"{name:6s} fell in: " + (", ".join(where) if where else "no segment"))
    if falls_plot:
        plot_falls(named, falls_plot)
    if plot:
        plt = _pyplot()
        walk = [s for s, v in segments(named[0][1]) if abs(v["command_vx"]) >= 0.05]
        if not walk:
            raise ValueError(f"--plot: {named[0][0]}'s schedule has no walking segment (|command v_x| >= 0.05 m/s) "
                             f"to draw; --plot-falls draws any schedule")
        fig, axes = plt.subplots(1, len(walk), figsize=(3.2 * len(walk), 3.6), sharey=True, squeeze=False)
        for ax, seg in zip(axes[0], walk):
            for i, (name, summary) in enumerate(named):
                s = summary[seg]
                v = np.array([x for x in s["vx"] if x is not None], float)
                ax.scatter(np.full(v.size, i) + np.random.default_rng(i).uniform(-0.25, 0.25, v.size),
                           v / s["command_vx"], s=5, alpha=0.5)
            ax.axhline(1.0, color="k", lw=0.8)
            ax.axhline(factor, color="r", lw=0.8, ls="--")
            ax.set_xticks(range(len(named)))
            ax.set_xticklabels([f"{n}\n{rows(sm, factor)[0]} fell" for n, sm in named], fontsize=8)
            ax.set_title(f"{seg}\n(v_x {named[0][1][seg]['command_vx']:+.1f} m/s)", fontsize=9)
        axes[0][0].set_ylabel("achieved / commanded v_x, per robot standing")
        fig.suptitle(f"eval_mjx --randomized: robots standing through each walk; red: {factor} x the command",
                     fontsize=10)
        fig.tight_layout()
        fig.savefig(plot, dpi=110)
        print(f"wrote {plot}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("summarize")
    s.add_argument("npz")
    s.add_argument("--commands", required=True, help="the schedule the rollout ran (eval_mjx.py --commands)")
    s.add_argument("--out", required=True)
    r = sub.add_parser("report")
    r.add_argument("summaries", nargs="+", metavar="NAME=ROBOTS.json")
    r.add_argument("--factor", type=float, default=1.5, help="running away: beyond this times the command")
    r.add_argument("--plot")
    r.add_argument("--plot-falls", metavar="FIG.png", help="the robots that fell per segment, one bar per rollout "
                   "(the rollouts must share one schedule)")
    args = ap.parse_args(argv)
    if args.cmd == "summarize":
        try:
            out = summarize(args.npz, args.commands)
        except (OSError, KeyError, ValueError) as e:
            sys.exit(f"segment_robots.py summarize: {e}")
        with open(args.out, "w") as f:
            json.dump(out, f)
        return
    if not args.factor > 1.0:
        ap.error(f"--factor {args.factor}: expected a factor above 1")
    named = []
    for item in args.summaries:
        name, _, path = item.rpartition("=")
        try:
            with open(path) as f:
                named.append((name or os.path.basename(path), json.load(f)))
        except (OSError, ValueError) as e:
            sys.exit(f"segment_robots.py report: {path}: {e}")
    try:
        report(named, args.factor, args.plot, args.plot_falls)
    except ValueError as e:
        sys.exit(f"segment_robots.py report: {e}")


if __name__ == "__main__":
    main()
