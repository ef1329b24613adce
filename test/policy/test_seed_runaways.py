#!/usr/bin/env python3
"""Tests scripts/seed_runaways.py (ctest seed_runaways_finds_hidden_runaways, label unit) on synthetic
pmg_policy_sil seed CSVs with known runaways: of three seeds, seed 11's stand drifts forward at 0.35 m/s in
the last 60 % of the segment (a runaway), seed 12's stop after a backward walk runs on at -0.25 m/s
(a runaway) and then it falls (damping mode), and seed 10 only walks at 1.3 times its forward command
(0.15 m/s over: not a runaway) and drifts 0.3 m/s in the first 40 % of its stand, outside the window
(not a runaway). A second episode of seed 10 (a restart, which follows a fall) moves at 1 m/s while
standing and must not count as a runaway; seed 10 counts as fallen. --segments 'stand_*' keeps seed 11 only. A CSV without the `episode` column is refused, naming
the file and the column.
Usage: test_seed_runaways.py
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "seed_runaways.py")
COLS = ["t", "segment", "vx_cmd", "vy_cmd", "wz_cmd", "vx", "vy", "wz", "mode", "episode"]


def write(path, segments, episode1=None, cols=COLS):
    """segments: [(name, vx_cmd, [vx per tick])]; 100 ticks each, vy = wz = 0."""
    rows, t = [], 0.0
    for ep, segs in ((0, segments), (1, episode1 or [])):
        for name, cmd, vxs in segs:
            for v in vxs:
                mode = "damping" if name == "FALL" else "active"
                rows.append({"t": f"{t:.2f}", "segment": name, "vx_cmd": cmd, "vy_cmd": 0, "wz_cmd": 0, "vx": v,
                             "vy": 0.0, "wz": 0.0, "mode": mode, "episode": ep})
                t += 0.01
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def run(*args):
    p = subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


def main():
    with tempfile.TemporaryDirectory() as d:
        write(os.path.join(d, "seed10.csv"), [("fwd0.5", 0.5, [0.65] * 100), ("stand_a", 0.0, [0.3] * 40 + [0.0] * 60)],
              episode1=[("stand_a", 0.0, [1.0] * 100)])
        write(os.path.join(d, "seed11.csv"), [("fwd0.5", 0.5, [0.5] * 100), ("stand_a", 0.0, [0.0] * 40 + [0.35] * 60)])
        write(os.path.join(d, "seed12.csv"), [("back0.5", -0.5, [-0.5] * 100), ("stop_back0.5", 0.0, [-0.25] * 100),
                                              ("FALL", 0.0, [0.0] * 3)])
        out = os.path.join(d, "r.json")
        rc, text = run(d, "--json", out)
        assert rc == 0, text
        r = json.load(open(out))
        assert r["seeds"] == 3, r
        assert r["runaway_seeds"] == [11, 12], r
        assert r["falls"] == [10, 12], r  # seed 10 restarted: a second episode follows only a fall
        assert [h["seed"] for h in r["segments"]["stand_a"]] == [11], r
        assert abs(r["segments"]["stand_a"][0]["achieved"] - 0.35) < 1e-6, r
        assert abs(r["segments"]["stop_back0.5"][0]["achieved"] + 0.25) < 1e-6, r
        assert "fwd0.5" not in r["segments"], r
        assert "2 of 3" in text, text
        rc, text = run(d, "--segments", "stand_*", "--json", out)
        r = json.load(open(out))
        assert rc == 0 and r["runaway_seeds"] == [11], text
        bad = os.path.join(d, "bad")
        os.mkdir(bad)
        write(os.path.join(bad, "seed1.csv"), [("stand_a", 0.0, [0.0] * 10)], cols=[c for c in COLS if c != "episode"])
        rc, text = run(bad)
        assert rc == 2 and "seed1.csv" in text and "'episode'" in text, text
        rc, text = run(os.path.join(d, "nothing"))
        assert rc == 2 and "no seed<N>.csv" in text, text
    print("seed_runaways: hidden runaways found, the others not; bad input refused")


if __name__ == "__main__":
    main()
