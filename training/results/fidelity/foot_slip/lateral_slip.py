#!/usr/bin/env python3
"""Why the lateral leg odometry reads low in side-steps: the stance soles slide.

Replays pmg_policy_sil's --probe CSV (MuJoCo's qpos/qvel when each loop tick read its state) in MuJoCo
and reports, per side-step segment (last 60 %), in the heading frame H, signed along the step:
  - the sole point's velocity in W of each foot by how many of its four contact spheres touch the floor;
  - leg odometry with exact kinematics (v_base - v_sole of the foot in the 2 cm stance band nearer the
    truth, gated at 0.15 m/s against the truth): what the estimator would read if its kinematics, IMU
    and gate were perfect. What remains is the stance sole's own slide. With --gate-centre estimate the
    choice and the gate are centred on the run's own estimate instead, as the estimator's are.
Segments named left*/right* are signed along the step; others (--segments PREFIX ...) are reported in H as they are,
forward (x) and left (y).
Usage (the training venv has mujoco):
  .venv-training/bin/python training/results/fidelity/foot_slip/lateral_slip.py OUT/probe.csv OUT/seed0.csv
      [--mjcf MJCF] [--segments PREFIX ...]
"""
import argparse
import csv
import os
import sys

import mujoco
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../.."))  # training/
from probe_sil import block, read_probe  # noqa: E402

P_FS = np.array([0.035, 0.0, -0.035])  # sole point in the foot link (include/pmg/gco/leg_kinematics.hpp)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("probe")
    ap.add_argument("seed_csv")
    ap.add_argument("--mjcf", default="config/robots/g1/g1_29dof_rev_1_0.xml")
    ap.add_argument("--segments", nargs="+", default=["left", "right"], metavar="PREFIX")
    ap.add_argument("--gate-centre", choices=["truth", "estimate"], default="truth",
                    help="what the emulated gate and nearest-foot choice are centred on: the true base velocity, or the "
                         "run's own estimate (seed CSV vx_est, vy_est), to see the gate's selection")
    args = ap.parse_args()
    probe, seed_csv, mjcf = args.probe, args.seed_csv, args.mjcf
    prefixes = tuple(args.segments)
    m = mujoco.MjModel.from_xml_path(mjcf)
    d = mujoco.MjData(m)
    cols = read_probe(probe)
    qpos, qvel = block(cols, "qpos"), block(cols, "qvel")
    seed_rows = list(csv.DictReader(open(seed_csv)))
    segs = [r["segment"] for r in seed_rows]
    feet = [m.body("left_ankle_roll_link").id, m.body("right_ankle_roll_link").id]
    per_seg = {}
    for k in range(min(len(qpos), len(segs))):
        if not segs[k].startswith(prefixes):
            continue
        d.qpos[:] = qpos[k]
        d.qvel[:] = qvel[k]
        mujoco.mj_forward(m, d)
        qw, qx, qy, qz = d.qpos[3:7]
        yaw = np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
        c, s = np.cos(yaw), np.sin(yaw)
        R_HW = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
        v_base = (R_HW @ d.qvel[0:3])[:2]
        z, v_leg, ncon, v_sole = np.zeros(2), np.zeros((2, 2)), [0, 0], np.zeros((2, 2))
        for f, b in enumerate(feet):
            R = d.xmat[b].reshape(3, 3)
            p = d.xpos[b] + R @ P_FS
            z[f] = p[2]
            jp = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, p, b)
            v_sole[f] = (R_HW @ (jp @ d.qvel))[:2]
            v_leg[f] = v_base - v_sole[f]
            ncon[f] = sum(1 for i in range(d.ncon)
                          if b in (m.geom_bodyid[d.contact[i].geom1], m.geom_bodyid[d.contact[i].geom2]))
        centre = v_base if args.gate_centre == "truth" else np.array(
            [float(seed_rows[k]["vx_est"]), float(seed_rows[k]["vy_est"])])
        per_seg.setdefault(segs[k], []).append((v_base, z, v_leg, ncon, v_sole, centre))
    for name, rows in per_seg.items():
        rows = rows[int(0.4 * len(rows)):]
        step = name.startswith(("left", "right"))
        sign = -1.0 if name.startswith("right") else 1.0
        by_contacts = {}
        acc, truth = [], []
        for v_base, z, v_leg, ncon, v_sole, centre in rows:
            for f in range(2):
                if ncon[f]:
                    by_contacts.setdefault(ncon[f], []).append(sign * v_sole[f])
            band = [f for f in range(2) if z[f] - z.min() <= 0.02]
            f = min(band, key=lambda f: np.hypot(*(v_leg[f] - centre)))
            if np.hypot(*(v_leg[f] - centre)) <= 0.15:
                acc.append(sign * v_leg[f])
                truth.append(sign * v_base)
        acc, truth = np.array(acc), np.array(truth)
        if step:
            print(f"{name}: {len(rows)} ticks; lateral along the step [m/s]")
            for n in sorted(by_contacts):
                print(f"  sole slide, {n} of 4 corners touching: {np.mean(by_contacts[n], axis=0)[1]:+.3f}"
                      f" ({len(by_contacts[n])} foot-ticks)")
            print(f"  exact leg odometry, accepted {len(acc)}: {acc[:, 1].mean():.3f} against the truth"
                  f" {truth[:, 1].mean():.3f} ({acc[:, 1].mean() - truth[:, 1].mean():+.3f})")
            continue
        print(f"{name}: {len(rows)} ticks; in H, (forward, left) [m/s]")
        for n in sorted(by_contacts):
            m = np.mean(by_contacts[n], axis=0)
            print(f"  sole slide, {n} of 4 corners touching: ({m[0]:+.3f}, {m[1]:+.3f}) ({len(by_contacts[n])} foot-ticks)")
        a, t = acc.mean(axis=0), truth.mean(axis=0)
        print(f"  exact leg odometry, accepted {len(acc)}: ({a[0]:.3f}, {a[1]:.3f}) against the truth"
              f" ({t[0]:.3f}, {t[1]:.3f}) ({a[0] - t[0]:+.3f}, {a[1] - t[1]:+.3f})")


if __name__ == "__main__":
    main()
