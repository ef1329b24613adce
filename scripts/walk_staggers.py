#!/usr/bin/env python3
"""Which walks make the robot stagger? Per walking segment of pmg_policy_sil runs: how many seeds
fell, latched the upset guard, were upset, or swayed sideways, in the walk or its stop
(docs/controller.md "Lean-back velocity envelope").

For every segment whose command moves (v_x, v_y or ω not zero) and every seed of each OUT_DIR
(its summary.json and seedN.csv), the walk's window is the segment itself and the segment after it
(the stop). In that window a seed counts as
  - fell:    a fall time (runs[].falls_s) inside it;
  - latched: an upset-guard latch time (runs[].upsets_s) inside it;
  - upset:   the walk segment's achieved mean more than UPSET (0.4 m/s or rad/s, one definition with
             scripts/fit_command_response.py) off its command on some axis;
  - swayed:  the achieved |v_y| above --sway (default 0.5 m/s) at some tick of the window while the
             command's v_y is 0 (a sideways stagger);
  - ran on:  still faster than 0.3 m/s along the walk's axis 1-3 s into the stop (mean over that
             span, scripts/stop_speed.py's measure): the robot did not stop when told.
Also printed: the walk's achieved v_x and torso pitch (means over seeds of the summary's segment
means) against the command. Several OUT_DIRs (the same script, other seeds) are pooled.

  python3 scripts/walk_staggers.py OUT_DIR [OUT_DIR ...] [--sway 0.5] [--json OUT.json]
Exit status 2 (with a message naming it) when an OUT_DIR has no summary.json or its scripts differ.
"""
import argparse
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fit_command_response import AXES, UPSET  # noqa: E402
from stop_speed import mean_speed  # noqa: E402

RAN_ON = 0.3  # [m/s] 1-3 s into the stop (docs/controller.md "Bent velocity envelope")


def load(out_dir):
    path = os.path.join(out_dir, "summary.json")
    if not os.path.isfile(path):
        raise SystemExit(f"walk_staggers: {path}: missing (a pmg_policy_sil --out directory expected)")
    with open(path) as f:
        return json.load(f)


def csv_rows(out_dir, seed):
    path = os.path.join(out_dir, f"seed{seed}.csv")
    if not os.path.isfile(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def windows(segments, rows):
    """[(walk index, name, t0, t1)] for the moving segments: the walk and the segment after it."""
    starts = {}
    for r in rows:
        starts.setdefault(r["segment"], float(r["t"]))
    out = []
    for i, s in enumerate(segments):
        c = s["command"]
        if c["vx"] == 0 and c["vy"] == 0 and c["wz"] == 0:
            continue
        t0 = starts.get(s["name"])
        nxt = segments[i + 2]["name"] if i + 2 < len(segments) else None
        t1 = starts.get(nxt, float("inf")) if nxt else float("inf")
        out.append((i, s["name"], t0, t1))
    return out


def score(out_dirs, sway):
    per_walk, script = {}, None
    for d in out_dirs:
        summary = load(d)
        if script is None:
            script = summary["commands"]
        elif summary["commands"] != script:
            raise SystemExit(f"walk_staggers: {d}: another script ({summary['commands']}, not {script})")
        for run in summary["runs"]:
            rows = csv_rows(d, run["seed"])
            segs = {s["name"]: s for s in run["segments"]}
            for i, name, t0, t1 in windows(summary["segments"], rows):
                w = per_walk.setdefault(name, {"order": i, "command": summary["segments"][i]["command"], "seeds": 0,
                                               "fell": [], "latched": [], "upset": [], "swayed": [], "ran_on": [],
                                               "vx": [], "pitch": []})
                if t0 is None:
                    continue  # the run ended before this walk
                w["seeds"] += 1
                tag = f"{os.path.basename(os.path.normpath(d))}:{run['seed']}"
                if any(t0 <= t < t1 for t in run.get("falls_s", [])):
                    w["fell"].append(tag)
                if any(t0 <= t < t1 for t in run.get("upsets_s", [])):
                    w["latched"].append(tag)
                seg = segs.get(name)
                if seg is not None and all(seg["achieved"].get(k) is not None for k in ("vx", "pitch", *AXES)):  # None: fell before its window
                    a, c = seg["achieved"], w["command"]
                    w["vx"].append(a["vx"])
                    w["pitch"].append(a["pitch"])
                    if any(abs(a[k] - c[k]) > UPSET for k in AXES):
                        w["upset"].append(tag)
                c = w["command"]
                axis = max(("vx", "vy", "wz"), key=lambda k: abs(c[k]))
                stop = summary["segments"][i + 1]["name"] if i + 1 < len(summary["segments"]) else None
                if stop is not None and abs(mean_speed(rows, stop, 1.0, 3.0, axis)) > RAN_ON:
                    w["ran_on"].append(tag)
                if w["command"]["vy"] == 0 and any(t0 <= float(r["t"]) < t1 and abs(float(r["vy"])) > sway for r in rows):
                    w["swayed"].append(tag)
    return sorted(per_walk.items(), key=lambda kv: kv[1]["order"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dirs", nargs="+")
    ap.add_argument("--sway", type=float, default=0.5, help="sideways speed that counts as a stagger [m/s]")
    ap.add_argument("--json", help="also write the table here")
    a = ap.parse_args(argv)
    table = score(a.out_dirs, a.sway)
    print(f"{'walk':34s} {'command (vx, vy, wz, pitch)':>27s} {'vx, pitch achieved':>18s} {'seeds':>5s} {'fell':>4s} "
          f"{'latched':>7s} {'upset':>5s} {'swayed':>6s} {'ran on':>6s}")
    for name, w in table:
        c = w["command"]
        vx = sum(w["vx"]) / len(w["vx"]) if w["vx"] else float("nan")
        pitch = sum(w["pitch"]) / len(w["pitch"]) if w["pitch"] else float("nan")
        print(f"{name[:34]:34s} {c['vx']:6.2f} {c['vy']:6.2f} {c['wz']:6.2f} {c['pitch']:6.2f} {vx:9.3f} {pitch:8.3f} "
              f"{w['seeds']:5d} {len(w['fell']):4d} {len(w['latched']):7d} {len(w['upset']):5d} {len(w['swayed']):6d} "
              f"{len(w['ran_on']):6d}")
        for k in ("fell", "latched", "upset", "swayed", "ran_on"):
            if w[k]:
                print(f"    {k}: {' '.join(w[k])}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"sway_m_s": a.sway, "upset": UPSET, "walks": [dict(name=n, **w) for n, w in table]}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
