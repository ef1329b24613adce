#!/usr/bin/env python3
"""eval_mjx.command_log on small seed CSVs whose command is known (plain NumPy; ctest training_command_log).

A log in pmg_policy_sil's seed<k>.csv layout (other columns beside the six it reads), one row per 0.01 s:
- two passive rows (the command columns nan): those ticks take the schedule's command;
- active rows whose command ramps: tick k takes the row at or before k dt, all six axes;
- after them a restarted episode (episode 1): not this run's command, so those ticks and every tick past
  the first episode's end take the schedule's again;
and bad logs, each refused naming the file, the row or column and the range: a missing column, a height
outside [0.3, 1.0] m, a time that goes back, a cell that is not a number."""
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import eval_mjx  # noqa: E402

failed = 0


def check(ok, what):
    global failed
    print(("ok   " if ok else "FAIL ") + what)
    failed += 0 if ok else 1


HEADER = ["t", "segment", "vx_cmd", "mode"] + eval_mjx.LOG_COLUMNS[:3] + ["vx_est", "pitch_fb", "roll_fb",
                                                                          "episode", "height_fb"]


def write(rows, header=HEADER):
    fd, path = tempfile.mkstemp(suffix=".csv", prefix="seed")
    with os.fdopen(fd, "w") as f:
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(str(x) for x in r) + "\n")
    return path


def row(k, c, episode=0, mode="active"):
    """A CSV row at tick k with the command c = (vx, vy, wz, pitch, roll, height) in its columns."""
    return [round(k * 0.01, 6), "walk", 0.3, mode, c[0], c[1], c[2], 0.0, c[3], c[4], episode, c[5]]


nan = float("nan")
sched = np.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.75])
at = lambda t: sched  # noqa: E731
cmd = lambda k: np.array([0.01 * k, -0.005 * k, 0.02 * k, 0.001 * k, -0.001 * k, 0.70 + 0.0001 * k])  # noqa: E731
rows = [row(0, [nan] * 6, mode="passive"), row(1, [nan] * 6, mode="passive")]
rows += [row(k, cmd(k)) for k in range(2, 40)]
rows += [row(k, cmd(k) * 0.0 + 0.5, episode=1) for k in range(20, 30)]  # the restarted robot's rows
path = write(rows)
log = eval_mjx.command_log(path, 60, 0.01, at)
check(log.shape == (60, 6), f"one command per tick: {log.shape}")
check(np.allclose(log[:2], sched), "ticks before the controller is active take the schedule's command")
check(np.allclose(log[2:40], np.stack([cmd(k) for k in range(2, 40)]), atol=1e-12),
      "active ticks take the logged command on all six axes, tick for tick")
check(np.allclose(log[40:], sched), "ticks past the first episode (a restart's rows ignored) take the schedule's")
# A coarser log (every other tick): a tick between two rows takes the earlier one.
coarse = eval_mjx.command_log(write([row(k, cmd(k)) for k in range(0, 40, 2)]), 40, 0.01, at)
check(np.allclose(coarse[7], cmd(6)) and np.allclose(coarse[8], cmd(8)), "a tick between rows takes the earlier row")

bad = {
    "missing column": (write([r[:-1] for r in rows], HEADER[:-1]), "no column height_fb"),
    "height out of range": (write([row(0, [0.0, 0.0, 0.0, 0.0, 0.0, 1.2])]), "height_fb = 1.2; expected in [0.3, 1]"),
    "time goes back": (write([row(5, cmd(5)), row(4, cmd(4))]), "row 3: t = 0.04 s after 0.05 s"),
    "not a number": (write([row(0, cmd(0))[:4] + ["x"] + row(0, cmd(0))[5:]]), "row 2: t, episode or"),
}
for what, (p, want) in bad.items():
    try:
        eval_mjx.command_log(p, 10, 0.01, at)
        msg = ""
    except ValueError as e:
        msg = str(e)
    check(want in msg and p in msg, f"{what}: refused naming the file and the field ({msg[len(p):][:90]})")
print(f"{failed} failed")
sys.exit(1 if failed else 0)
