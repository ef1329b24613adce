#!/usr/bin/env python3
"""scripts/stop_speed.py: on two synthetic seeds, one that stops and one that walks on, the mean speed
1-3 s into the stop is found per seed on the segment's own axis, the seed beyond the threshold is
counted (on the name's axis, or the one --axis names), a seed that fell before the segment is nan and not counted, and a missing segment or an empty
directory ends with exit status 2 naming it."""
import csv
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "stop_speed.py")


def write_seed(d, k, v_stop, t_end=6.0, side=0.0):
    with open(os.path.join(d, f"seed{k}.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "segment", "vx", "vy", "wz"])
        for i in range(int(t_end * 100)):
            t = i / 100
            if t < 2.0:
                w.writerow([t, "walk", 1.0, 0.0, 0.0])
            elif t < 5.0:
                # 0.5 m/s during the first second of the stop (not in the 1-3 s window), then v_stop
                w.writerow([t, "stop_fwd", 0.5 if t < 3.0 else v_stop, side, 0.0])
            else:
                w.writerow([t, "stop_side", 0.0, side, 0.0])


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def main():
    with tempfile.TemporaryDirectory() as d:
        write_seed(d, 0, 0.02)
        write_seed(d, 1, 0.8, side=0.4)
        write_seed(d, 2, 0.0, t_end=1.0)  # fell in the walk
        r = run(d, "stop_fwd", "stop_side")
        assert r.returncode == 0, r.stderr
        assert "stop_side 0 of 0" in r.stdout.splitlines()[-1], r.stdout  # 1 s long: the 1-3 s window is empty
        lines = r.stdout.splitlines()
        row = {l.split()[0]: l.split()[1:] for l in lines if l.startswith("seed") and not l.startswith("seed ")}
        assert abs(float(row["seed0"][0]) - 0.02) < 1e-9, row
        assert abs(float(row["seed1"][0]) - 0.8) < 1e-9, row
        assert row["seed2"][0] == "nan", row
        assert "stop_fwd 1 of 2" in lines[-1], lines[-1]
        # with --from-s 0 stop_side's axis is v_y: seed 1 moves 0.4 m/s sideways
        r = run(d, "stop_side", "--from-s", "0", "--to-s", "1")
        assert r.returncode == 0, r.stderr
        assert "stop_side 1 of 2" in r.stdout.splitlines()[-1], r.stdout
        # --axis vy for every segment: stop_fwd's v_y is 0.4 in seed 1 from 2 s on (1-3 s into it)
        r = run(d, "stop_fwd", "--axis", "vy")
        assert r.returncode == 0 and "stop_fwd 1 of 2" in r.stdout.splitlines()[-1], r.stdout
        r = run(d, "stop_back")
        assert r.returncode == 2 and "stop_back" in r.stderr, r
    with tempfile.TemporaryDirectory() as d:
        r = run(d, "stop_fwd")
        assert r.returncode == 2 and "no seedN.csv" in r.stderr, r
    print("ok")


if __name__ == "__main__":
    main()
