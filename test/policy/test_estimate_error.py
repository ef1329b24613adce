#!/usr/bin/env python3
"""scripts/estimate_error.py: on a synthetic run with known estimate errors (v_x off by 0.1 m/s on
every tick, v_y by 0.5 m/s on one tick in ten, the yaw rate exact), the RMS and the share of ticks
beyond the limits come out as built; ticks outside active and ticks with a nan estimate are left out;
a directory without seed<k>.csv is refused, naming it."""
import csv
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "estimate_error.py")


def main():
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "seed0.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t", "mode", "vx", "vy", "wz", "vx_est", "vy_est", "wz_est"])
            for i in range(1000):
                vy_err = 0.5 if i % 10 == 0 else 0.0
                w.writerow([i / 100, "active", 0.4, 0.1, 0.2, 0.5, 0.1 + vy_err, 0.2])
            w.writerow([10.0, "damping", 0.0, 0.0, 0.0, 9.0, 9.0, 9.0])  # not active: left out
            w.writerow([10.01, "active", 0.0, 0.0, 0.0, "nan", "nan", "nan"])  # feedback off: left out
        r = subprocess.run([sys.executable, SCRIPT, d], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        out = r.stdout
        assert "1000 ticks" in out, out
        assert "RMS v_x 0.100 m/s" in out, out
        assert f"v_y {math.sqrt(0.1 * 0.25):.3f} m/s" in out, out
        assert "yaw rate 0.000 rad/s" in out, out
        assert "0.00 % / 10.00 % / 0.00 %" in out, out  # v_x 0.1 is within 0.3
    with tempfile.TemporaryDirectory() as d:
        r = subprocess.run([sys.executable, SCRIPT, d], capture_output=True, text=True)
        assert r.returncode != 0 and "no seed<k>.csv" in r.stderr, r


if __name__ == "__main__":
    main()
    print("ok")
