#!/usr/bin/env python3
"""Tests training/segment_robots.py on a synthetic randomized rollout (ctest segment_robots_finds_the_runaway,
label unit). Three robots on a schedule stand 0-1 s, walk backward at -0.3 m/s 1-3 s, stop 3-4 s:
- robot 0 tracks (-0.3 m/s, feet down), robot 1 runs away (-0.6 m/s, both feet off the floor in every
  other tick of the walk), robot 2 falls at 2.0 s, inside the walk's window (last 60 %: 1.8-3 s);
- summarize gives the walk's v_x (-0.3, -0.6, None), flight (0, 0.5, None), fallen_by_end (no, no, yes),
  and the stop None for robot 2; the drawn friction comes along;
- the report row: 1 of 3 fallen by the end, the walk's median -0.45 m/s and 1 of the 2 standing robots
  beyond 1.5 x the command (none beyond 2.5 x); the stand and the stop are not walking segments; a walk
  no robot stood through says so (not nan);
- the falls per segment: robot 2 in the walk, none in the stand or the stop (a robot fallen earlier is not
  counted again);
- a rollout longer than the schedule is refused, naming both; --plot and --plot-falls write their figures, and
  --plot-falls refuses rollouts of different schedules, naming the rollout; --plot refuses a schedule without
  a walk, saying so.
Usage: test_segment_robots.py
"""
import contextlib
import copy
import io
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "training", "segment_robots.py")
sys.path.insert(0, os.path.join(ROOT, "training"))
import segment_robots as sr  # noqa: E402
from script_checks import Checks  # noqa: E402  (beside this file)

check = Checks()


def rollout(path, ticks=400, dt=0.01):
    t = np.arange(ticks) * dt
    meas = np.zeros((3, ticks, 8), np.float32)
    meas[:, :, 4:6] = 1.0  # both feet down
    walk = (t >= 1.0) & (t < 3.0)
    meas[0, walk, 0] = -0.3
    meas[1, walk, 0] = -0.6
    odd = np.zeros(ticks, bool)
    odd[1::2] = True
    meas[1, walk & odd, 4:6] = 0.0  # in flight every other tick of the walk
    meas[2, walk, 0] = -0.3
    done = np.zeros((3, ticks), np.float32)
    done[2, t >= 2.0] = 1.0
    np.savez(path, t=t, measured=meas, done=done, drawn_friction=np.array([0.6, 0.8, 1.0], np.float32),
             drawn_mass=np.array([35.0, 36.0, 37.0], np.float32))


def main():
    with tempfile.TemporaryDirectory() as d:
        sched = os.path.join(d, "s.yaml")
        with open(sched, "w") as f:
            f.write("ramp: 0.0\nduration: 4.0\nsegments:\n"
                    "  - {name: stand, t: 0, vx: 0, vy: 0, wz: 0, pitch: 0, roll: 0, height: 0.74}\n"
                    "  - {name: back, t: 1, vx: -0.3, vy: 0, wz: 0, pitch: 0, roll: 0, height: 0.74}\n"
                    "  - {name: stop, t: 3, vx: 0, vy: 0, wz: 0, pitch: 0, roll: 0, height: 0.74}\n")
        npz = os.path.join(d, "r.npz")
        rollout(npz)
        out = os.path.join(d, "robots.json")
        subprocess.run([sys.executable, SCRIPT, "summarize", npz, "--commands", sched, "--out", out], check=True)
        with open(out) as f:
            s = json.load(f)
        b = s["back"]
        check(b["command_vx"] == -0.3 and b["vx"] == [-0.3, -0.6, None] and b["flight"] == [0.0, 0.5, None]
              and b["fallen_by_end"] == [False, False, True],
              f"the walk per robot: v_x {b['vx']}, flight {b['flight']}, fallen {b['fallen_by_end']}")
        check(s["stop"]["vx"][2] is None and s["stop"]["vx"][:2] == [0.0, 0.0] and s["stand"]["fallen_by_end"] ==
              [False, False, False] and s["drawn_friction"] == [0.6, 0.8, 1.0],
              f"the stop: {s['stop']['vx']}; the stand: no fall; friction {s['drawn_friction']}")
        fallen, rows = sr.rows(s, 1.5)
        check(fallen == 1 and len(rows) == 1 and rows[0][0] == "back" and abs(rows[0][2] + 0.45) < 1e-9 and
              rows[0][3] == 0.5 and rows[0][4] == 0.25 and rows[0][5] == 2,
              f"report row: {fallen} fallen; {rows}")
        check(sr.rows(s, 2.5)[1][0][3] == 0.0, "none of them beyond 2.5 x the command")
        check(sr.fell_in(s) == [("stand", 0), ("back", 1), ("stop", 0)],
              f"falls per segment: {sr.fell_in(s)} (robot 2 in the walk, not again in the stop)")
        gone = copy.deepcopy(s)  # every robot fell before the walk's window: said so, not printed as nan
        gone["back"]["vx"], gone["back"]["flight"] = [None] * 3, [None] * 3
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            sr.report([("G", gone)], 1.5)
        check("back no robot standing (0)" in buf.getvalue() and "nan" not in buf.getvalue(),
              f"a walk no robot stood through: {buf.getvalue().splitlines()[-2].strip()}")
        long_npz = os.path.join(d, "long.npz")
        rollout(long_npz, ticks=500)
        p = subprocess.run([sys.executable, SCRIPT, "summarize", long_npz, "--commands", sched, "--out", out],
                           capture_output=True, text=True)
        check(p.returncode != 0 and "long.npz" in p.stderr and "s.yaml" in p.stderr and "4.0 s" in p.stderr,
              f"a rollout longer than its schedule refused: {p.stderr.strip()}")
        png = os.path.join(d, "fig.png")
        p = subprocess.run([sys.executable, SCRIPT, "report", f"A={out}", "--plot", png], capture_output=True,
                           text=True)
        check(p.returncode == 0 and os.path.getsize(png) > 1000 and "fallen   1/3" in p.stdout,
              f"report --plot: {p.stdout.strip().splitlines()[-2] if p.stdout else p.stderr}")
        falls_png = os.path.join(d, "falls.png")
        p = subprocess.run([sys.executable, SCRIPT, "report", f"A={out}", f"B={out}", "--plot-falls", falls_png],
                           capture_output=True, text=True)
        check(p.returncode == 0 and os.path.getsize(falls_png) > 1000 and "A      fell in: back 1" in p.stdout,
              f"report --plot-falls: {p.stdout.strip().splitlines()[-2] if p.stdout else p.stderr}")
        other = copy.deepcopy(s)
        other["stop_2"] = other.pop("stop")
        other_json = os.path.join(d, "other.json")
        with open(other_json, "w") as f:
            json.dump(other, f)
        p = subprocess.run([sys.executable, SCRIPT, "report", f"A={out}", f"C={other_json}", "--plot-falls",
                            falls_png], capture_output=True, text=True)
        check(p.returncode != 0 and "C:" in p.stderr and "schedule" in p.stderr,
              f"--plot-falls on two schedules refused: {p.stderr.strip()}")
        still = copy.deepcopy(s)  # a schedule without a walk (the floor stops' side-steps and turns): --plot says so
        still["back"]["command_vx"] = 0.0
        still_json = os.path.join(d, "still.json")
        with open(still_json, "w") as f:
            json.dump(still, f)
        p = subprocess.run([sys.executable, SCRIPT, "report", f"S={still_json}", "--plot", png], capture_output=True,
                           text=True)
        check(p.returncode != 0 and "no walking segment" in p.stderr and "Traceback" not in p.stderr,
              f"--plot on a schedule without a walk refused: {p.stderr.strip()}")
    return check.exit_code()


if __name__ == "__main__":
    sys.exit(main())
