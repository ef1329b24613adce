#!/usr/bin/env python3
"""scripts/standing_reference.py: on two synthetic seeds whose reference holds a known toe-out (hip yaw), hip roll and
knee split in one standing segment, the table gives each segment's largest and mean values over the seeds; walking
segments and --restart-after-fall's restart segments are left out; a file without the qref columns and an empty
directory end with exit status 2 naming them."""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "standing_reference.py")
HEADER = ["t", "segment", "vx_cmd", "vy_cmd", "wz_cmd"] + [f"qref{i}" for i in range(12)]


def leg_pose(yaw_r=0.0, roll_l=0.0, knee_l=0.3, knee_r=0.3):
    q = [-0.1, 0.0, 0.0, 0.3, -0.2, 0.0] * 2
    q[1], q[3] = roll_l, knee_l
    q[8], q[9] = yaw_r, knee_r
    return q


def write_seed(d, k, yaw_r, roll_l, knee_l, restart=False):
    with open(os.path.join(d, f"seed{k}.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        t = 0.0
        for seg, cmd, q, n in (("stand", (0, 0, 0), leg_pose(), 50),
                               ("back_0.50", (-0.5, 0, 0), leg_pose(yaw_r=-0.9, knee_l=1.2), 50),
                               ("stand_2", (0, 0, 0), leg_pose(yaw_r, roll_l, knee_l), 50)):
            for _ in range(n):
                w.writerow([f"{t:.2f}", seg, *cmd, *q])
                t += 0.01
        if restart:
            for _ in range(10):
                w.writerow([f"{t:.2f}", "restart_stand", 0, 0, 0, *leg_pose(yaw_r=2.0)])
                t += 0.01


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def main():
    with tempfile.TemporaryDirectory() as d:
        write_seed(d, 0, -0.36, 0.05, 0.30)
        write_seed(d, 1, -0.20, -0.11, 0.60, restart=True)
        out = os.path.join(d, "t.json")
        r = run(d, "--json", out)
        assert r.returncode == 0, r.stderr
        segs = {s["segment"]: s for s in json.load(open(out))["segments"]}
        assert set(segs) == {"stand", "stand_2"}, segs  # the walk and the restart are not standing segments
        s = segs["stand_2"]
        assert s["seeds"] == 2
        assert abs(s["hip_yaw"]["max"] - 0.36) < 1e-12 and abs(s["hip_yaw"]["mean"] - 0.28) < 1e-12, s
        assert abs(s["hip_roll"]["max"] - 0.11) < 1e-12 and abs(s["hip_roll"]["mean"] - 0.08) < 1e-12, s
        assert abs(s["knee_difference"]["max"] - 0.30) < 1e-12 and abs(s["knee_difference"]["mean"] - 0.15) < 1e-12, s
        assert segs["stand"]["hip_yaw"]["max"] == 0.0 and segs["stand"]["knee_difference"]["max"] == 0.0, segs
        assert "stand_2" in r.stdout and "0.360" in r.stdout, r.stdout
        with open(os.path.join(d, "seed2.csv"), "w") as f:
            f.write("t,segment,vx_cmd,vy_cmd,wz_cmd\n0,stand,0,0,0\n")
        r = run(d)
        assert r.returncode == 2 and "seed2.csv" in r.stderr and "qref0" in r.stderr, r
    with tempfile.TemporaryDirectory() as d:
        r = run(d)
        assert r.returncode == 2 and "no seedN.csv" in r.stderr, r
    print("ok")


if __name__ == "__main__":
    main()
