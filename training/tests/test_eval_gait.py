#!/usr/bin/env python3
"""eval_mjx.segment_gait on contact sequences whose gait is known (plain NumPy; ctest training_eval_gait).

Two robots at 100 Hz over three 5-s segments (each window, the last 3 s, holds whole gait cycles):
- "walk": a 1-s gait cycle, each foot on the floor for 60 % of it, half a cycle apart: 20 % double support,
  no flight, one contact onset per second per foot, the touching feet still (0 m/s);
- "hop": a 0.5-s cycle, both feet down for 0.3 s and up for 0.2 s: 40 % flight, 60 % double support, two
  onsets per second per foot, the touching feet sliding at 0.5 m/s;
- "fallen": robot 0 fell half a second into the hop's window, and robot 1 hops on; the segment pools robot 1 alone (its
  gait is the hop's), and a segment where no robot is alive gives None.
The window is the last 60 % of each segment, as pmg_policy_sil's."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import eval_mjx  # noqa: E402

dt = 0.01
t = np.arange(1500) * dt
spans = [("walk", 0.0, 5.0), ("hop", 5.0, 10.0), ("fallen", 10.0, 15.0)]
contact = np.zeros((2, t.size, 2), bool)
speed = np.zeros((2, t.size, 2))
k = np.arange(t.size)  # ticks: the cycles in whole ticks, free of rounding
walk = k < 500
contact[:, walk, 0] = k[walk] % 100 < 60
contact[:, walk, 1] = (k[walk] + 50) % 100 < 60
hop = ~walk
down = k[hop] % 50 < 30
contact[:, hop, :] = down[None, :, None]
speed[:, hop, :] = 0.5
alive = np.ones((2, t.size), bool)
alive[0, t >= 7.5] = False
# robot 1's feet swing at 2 m/s while off the floor: a swing is not a slip
speed[1][~contact[1]] = 2.0

failures = []
gait = eval_mjx.segment_gait(t, contact, speed, spans, alive, dt)
want = {"walk": (0.0, 0.2, 1.0, 0.0), "hop": (0.4, 0.6, 2.0, 0.5), "fallen": (0.4, 0.6, 2.0, 0.5)}
for (name, _, _), g in zip(spans, gait):
    got = (g["flight"], g["double"], g["touchdowns_per_s"], g["slip"])
    tol = (1e-9, 1e-9, 1e-9, 1e-9)
    if any(abs(a - b) > e for a, b, e in zip(got, want[name], tol)):
        failures.append(f"{name}: flight, double, onsets/s, slip = {np.round(got, 3).tolist()}, want {want[name]}")
none = eval_mjx.segment_gait(t, contact, speed, [("after", 10.0, 15.0)], np.zeros_like(alive), dt)
if none != [None]:
    failures.append(f"no robot alive: {none}, want [None]")
for f in failures:
    print("FAIL:", f)
print("segment_gait:", "ok" if not failures else f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
