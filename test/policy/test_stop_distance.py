#!/usr/bin/env python3
"""scripts/stop_distance.py --segments: on a synthetic two-seed run of a script with two walks and
their stops (stand, walk1, stop1, stand1, walk2, stop2, stand2), where seed 1 goes on at 0.4 m/s for
3 s after the second stop's command reached zero (1.2 m) and every other stop is still at once, it
reports 4 stops, a largest distance of 1.2 m and one stop beyond 1 m; the distance starts only once
the command is zero (the stop's ramp is not counted); a stop the run never reached is left out; a
directory without summary.json is refused, naming it."""
import csv
import json
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "stop_distance.py")
SEGS = [("stand", 0.0), ("walk1", 2.0), ("stop1", 5.0), ("stand1", 8.0), ("walk2", 10.0), ("stop2", 13.0),
        ("stand2", 16.0)]


def write_run(d, end_t=20.0):
    for seed in (0, 1):
        with open(os.path.join(d, f"seed{seed}.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t", "segment", "vx_cmd", "vx", "episode"])
            for i in range(int(end_t * 100)):
                t = i / 100
                name, start = [s for s in SEGS if s[1] <= t][-1]
                cmd = 0.5 if name.startswith("walk") else (max(0.0, 0.5 - (t - start)) if name.startswith("stop") else 0.0)
                vx = cmd  # still at once ...
                if seed == 1 and name in ("stop2", "stand2") and 13.5 <= t < 16.5:
                    vx = 0.4  # ... but seed 1 runs on 3 s after the second stop's command reached zero
                w.writerow([f"{t:.2f}", name, cmd, vx, 0])
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"runs": [{"seed": 0, "fell": False}, {"seed": 1, "fell": False}]}, f)


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def main():
    with tempfile.TemporaryDirectory() as d:
        write_run(d)
        r = run(d, "--segments", "stop1,stop2")
        assert r.returncode == 0, r.stderr
        out = r.stdout
        assert "4 stops" in out, out
        largest = float(re.search(r"largest ([0-9.]+) m", out).group(1))
        assert abs(largest - 1.2) < 0.02, out
        assert "> 1 m: 1" in out and "> 0.5 m: 1" in out, out
        assert "median 0.00 m" in out, out  # the ramp before the command reaches zero is not counted
    with tempfile.TemporaryDirectory() as d:
        write_run(d, end_t=12.0)  # the run ends before the second stop
        r = run(d, "--segments", "stop1,stop2")
        assert r.returncode == 0 and "2 stops" in r.stdout, (r.stdout, r.stderr)
    with tempfile.TemporaryDirectory() as d:
        r = run(d, "--segments", "stop1")
        assert r.returncode != 0 and "summary.json: missing" in (r.stderr + r.stdout), r


if __name__ == "__main__":
    main()
    print("ok")
