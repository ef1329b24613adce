#!/usr/bin/env python3
"""Tests training/plot_checkpoints.py on synthetic eval_mjx.py rollouts of a run's kept actors (ctest
plot_checkpoints_tracks_a_forming_gait, label unit). Three checkpoints, written out of step order, of a schedule with
a backward walk (commanded -0.5 m/s) and a stop:
- at 10 M steps the robot fell in the walk (NaN), at 50 M it runs (-1.0 m/s), at 200 M it walks -0.55 m/s;
- the table lists them in step order, marks -0.55 in issue 12's band (15 % of 0.5: 0.075) and -1.0 out of it, and
  says "fell" for the NaN;
- in_band: 15 % or the axis's floor (0.05 m/s for v_x: -0.04 for 0 is in, -0.06 is not);
- a file without actor_<step> in its name, and a segment the rollouts do not have, are refused naming them;
- eval_mjx.py's printed table (.txt) reads as its npz does, "fell" as NaN; a text without the table is refused;
- --out writes the figure.
Usage: test_plot_checkpoints.py
"""
import contextlib
import io
import os
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "training"))
import plot_checkpoints as pc  # noqa: E402
from script_checks import Checks  # noqa: E402  (beside this file)

check = Checks()


def rollout(path, walk_vx, stop_vx):
    names = np.array(["back0.5", "stop"])
    command = np.zeros((2, 6))
    command[0, 0] = -0.5
    achieved = np.zeros((2, 6))
    achieved[:, 0] = [walk_vx, stop_vx]
    np.savez(path, segment_names=names, segment_command=command, segment_achieved=achieved)


def run(argv):
    buf = io.StringIO()
    code = 0
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
        try:
            pc.main(argv)
        except SystemExit as e:
            code = e.code if isinstance(e.code, int) else 1
            print(e.code)
    return code, buf.getvalue()


with tempfile.TemporaryDirectory() as d:
    rollout(os.path.join(d, "R_actor_00200000000.npz"), -0.55, -0.02)
    rollout(os.path.join(d, "R_actor_00010000000.npz"), np.nan, np.nan)
    rollout(os.path.join(d, "R_actor_00050000000.npz"), -1.0, -0.6)
    code, out = run([f"R={d}/R_actor_*.npz", "--segments", "back0.5", "stop"])
    print(out)
    rows = [l.split() for l in out.splitlines() if l.startswith("R ")]
    check(code == 0 and [r[1] for r in rows] == ["10.0", "50.0", "200.0"], "checkpoints listed in step order")
    check(rows and rows[0][2] == "fell", "a fallen robot says fell")
    check(len(rows) == 3 and rows[1][2] == "-1.000" and rows[2][2] == "-0.550*", "-1.0 out of the band, -0.55 in it")
    check(len(rows) == 3 and rows[2][4] == "-0.020*" and rows[1][4] == "-0.600", "the stop: -0.02 in, -0.6 out")
    check(pc.in_band(0.0, -0.04, "vx") and not pc.in_band(0.0, -0.06, "vx"), "the band's floor 0.05 m/s at command 0")
    check(pc.in_band(-0.5, -0.57, "vx") and not pc.in_band(-0.5, -0.58, "vx"), "the band's 15 % of -0.5 m/s")
    check(not pc.in_band(-0.5, float("nan"), "vx"), "NaN is never in the band")
    rollout(os.path.join(d, "R_final.npz"), -0.5, 0.0)
    code, out = run([f"R={d}/R_*.npz", "--segments", "back0.5"])
    check(code != 0 and "R_final.npz" in out and "actor_<step>" in out, "a file without a step is refused by name")
    os.remove(os.path.join(d, "R_final.npz"))
    code, out = run([f"R={d}/R_actor_*.npz", "--segments", "back0.3"])
    check(code != 0 and "'back0.3'" in out and "back0.5" in out, "a missing segment is refused, naming what is there")
    code, out = run([f"R={d}/nothing_*.npz", "--segments", "back0.5"])
    check(code != 0 and "no file matches" in out, "a pattern matching nothing is refused")
    # The printed form of a rollout (eval_mjx.py's table: name, commanded/achieved per axis, reward).
    table = ["physics: MJX", "per segment (means over the last 60 % of each segment): commanded / achieved, and "
             "the reward per step (the actor)", "segment   vx  vy  wz  pitch  roll  height  reward",
             "back0.5   -0.500 -0.400 0 0.010 0 0 0 0.020 0 -0.010 0.740 0.752 6.000",
             "stop_after_back0.5_long   0 fell 0 fell 0 fell 0 fell 0 fell 0.740 fell    fell",
             "reward per step by term (same windows)"]
    with open(os.path.join(d, "T_actor_00150000000.txt"), "w") as f:
        f.write("\n".join(table) + "\n")
    names, command, achieved = pc.read_rollout(os.path.join(d, "T_actor_00150000000.txt"))
    check(names == ["back0.5", "stop_after_back0.5_long"] and command.shape == (2, 6), "the text table's rows")
    check(achieved[0, 0] == -0.4 and achieved[0, 3] == 0.02 and achieved[0, 5] == 0.752 and command[0, 5] == 0.74,
          "the text table's commanded and achieved columns in KEYS' order")
    check(bool(np.all(np.isnan(achieved[1]))) and command[1, 5] == 0.74, "'fell' reads as NaN")
    code, out = run([f"T={d}/T_actor_*.txt", "--segments", "back0.5"])
    check(code == 0 and "-0.400" in out and "150.0" in out, "a run of text rollouts is tabled")
    with open(os.path.join(d, "U_actor_00150000000.txt"), "w") as f:
        f.write("Traceback (most recent call last):\n")
    code, out = run([f"U={d}/U_actor_*.txt", "--segments", "back0.5"])
    check(code != 0 and "U_actor_00150000000.txt" in out and "per segment" in out, "a text without the table is refused")
    try:
        import matplotlib  # noqa: F401
        png = os.path.join(d, "c.png")
        code, out = run([f"R={d}/R_actor_*.npz", "--segments", "back0.5", "stop", "--warmup-steps", "135e6",
                         "--out", png])
        check(code == 0 and os.path.getsize(png) > 10000, "--out writes the figure")
    except ImportError:
        print("skip the figure: no matplotlib")

sys.exit(check.exit_code())
