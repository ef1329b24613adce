#!/usr/bin/env python3
"""scripts/walk_staggers.py: on a synthetic two-seed run of a one-walk script (stand, walk 1.0 m/s
leaning back, stop, stand) with the effects hidden in seed 1 (a sideways sway beyond 0.5 m/s in the
walk, an upset-guard latch and a fall in the stop, the walk's mean 0.5 m/s off its command, still
0.6 m/s forward 1-3 s into the stop) and none in seed 0, each count comes out 0 for seed 0 and 1 for
seed 1, and the JSON lists them; standing segments are not walks; a directory without summary.json
is refused, naming it; a seed without achieved values in the walk (fell before its window) is run,
not averaged."""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "walk_staggers.py")
SEGS = [("stand", 0.0, 0.0), ("walk", 2.0, 1.0), ("stop", 6.0, 0.0), ("upright", 9.0, 0.0)]  # name, start, v_x


def command(vx):
    return {"vx": vx, "vy": 0.0, "wz": 0.0, "pitch": -0.1 if vx else 0.0, "roll": 0.0, "height": 0.78}


def write_run(d):
    runs = []
    for seed in (0, 1):
        bad = seed == 1
        with open(os.path.join(d, f"seed{seed}.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t", "segment", "vx", "vy", "wz"])
            for i in range(1200):
                t = i / 100
                name = [s for s in SEGS if s[1] <= t][-1][0]
                vx = {"walk": 1.0, "stop": 0.6 if bad else 0.0}.get(name, 0.0)
                vy = 0.7 if bad and name == "walk" and 4.0 <= t < 4.2 else 0.05
                w.writerow([t, name, vx, vy, 0.0])
        achieved = {n: command(v) for n, _, v in SEGS}
        if bad:
            achieved["walk"] = dict(command(1.0), vx=0.5)
        runs.append({"seed": seed, "falls_s": [7.5] if bad else [], "upsets_s": [6.5] if bad else [],
                     "segments": [{"name": n, "achieved": achieved[n]} for n, _, _ in SEGS]})
    summary = {"commands": "synthetic.yaml", "runs": runs,
               "segments": [{"name": n, "command": command(v)} for n, _, v in SEGS]}
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump(summary, f)


def main():
    with tempfile.TemporaryDirectory() as d:
        out_dir = os.path.join(d, "run")
        os.mkdir(out_dir)
        write_run(out_dir)
        table = os.path.join(d, "t.json")
        r = subprocess.run([sys.executable, SCRIPT, out_dir, "--json", table], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        walks = json.load(open(table))["walks"]
        assert [w["name"] for w in walks] == ["walk"], walks  # stand, stop and upright are not walks
        w = walks[0]
        assert w["seeds"] == 2, w
        for key in ("fell", "latched", "upset", "swayed", "ran_on"):
            assert w[key] == ["run:1"], (key, w[key], r.stdout)
        assert abs(sum(w["vx"]) / 2 - 0.75) < 1e-9, w["vx"]
        assert "walk" in r.stdout and "ran_on: run:1" in r.stdout, r.stdout
    # A seed that fell before the walk's averaging window has no achieved values there (null): it is
    # counted as run, its staggers still, but it adds nothing to the walk's mean.
    with tempfile.TemporaryDirectory() as d:
        out_dir = os.path.join(d, "run")
        os.mkdir(out_dir)
        write_run(out_dir)
        path = os.path.join(out_dir, "summary.json")
        summary = json.load(open(path))
        summary["runs"][1]["segments"][1]["achieved"] = {k: None for k in command(0.0)}
        json.dump(summary, open(path, "w"))
        table = os.path.join(d, "t.json")
        r = subprocess.run([sys.executable, SCRIPT, out_dir, "--json", table], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        w = json.load(open(table))["walks"][0]
        assert w["seeds"] == 2 and w["vx"] == [1.0] and w["fell"] == ["run:1"] and w["upset"] == [], w
    with tempfile.TemporaryDirectory() as d:
        r = subprocess.run([sys.executable, SCRIPT, d], capture_output=True, text=True)
        assert r.returncode != 0 and "summary.json: missing" in (r.stderr + r.stdout), r


if __name__ == "__main__":
    main()
    print("ok")
