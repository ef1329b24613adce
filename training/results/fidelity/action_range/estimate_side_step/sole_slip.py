#!/usr/bin/env python3
"""How fast the stance soles slide in a side-step: the point leg odometry holds still (the sole point S,
(0.035, 0, -0.035) m in the ankle-roll frame, include/pmg/gco/leg_kinematics.hpp), in the MuJoCo state that
`pmg_policy_sil --probe` wrote, at ticks where that foot has 3 or more penetrating contacts (the sole lies flat).

  build/bin/pmg_policy_sil --commands training/results/fidelity/action_range/estimate_side_step/side_step_0.70.yaml \\
      --seeds 1 --first-seed 36 --probe P70.csv --out OUT70
  .venv-training/bin/python training/results/fidelity/action_range/estimate_side_step/sole_slip.py P70.csv [--t0 8.2 --t1 12]

Prints, for the window [t0, t1) s: the pelvis's true v_y (heading frame H) and, per foot, the share of ticks lying
flat and the sole point's mean v_x, v_y (H) there [m/s]. A sole held still reads 0; a positive v_y in a left
side-step is a sole sliding along with the robot, which leg odometry takes for the pelvis moving that much slower.
Run from the repository root (the MJCF path is relative to it); MuJoCo 3 (the training venv) loads the SIL's MJCF.
"""
import argparse
import csv

import mujoco
import numpy as np

MJCF = "config/robots/g1/g1_29dof_rev_1_0.xml"
SOLE_F = np.array([0.035, 0.0, -0.035])  # the sole point in the ankle-roll frame [m]


def heading(qpos):
    """The pelvis yaw [rad] from the free joint's quaternion (w, x, y, z)."""
    w, x, y, z = qpos[3:7]
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("probe", help="pmg_policy_sil --probe CSV")
    ap.add_argument("--t0", type=float, default=8.2)
    ap.add_argument("--t1", type=float, default=12.0)
    args = ap.parse_args()
    m = mujoco.MjModel.from_xml_path(MJCF)
    d = mujoco.MjData(m)
    feet = {"left": mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "left_ankle_roll_link"),
            "right": mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "right_ankle_roll_link")}
    with open(args.probe) as f:
        rows = csv.reader(f)
        hdr = next(rows)
        iq = [hdr.index(f"qpos{i}") for i in range(m.nq)]
        iv = [hdr.index(f"qvel{i}") for i in range(m.nv)]
        truth, flat = [], {k: [] for k in feet}
        for r in rows:
            if not args.t0 <= float(r[0]) < args.t1:
                continue
            d.qpos[:] = [float(r[i]) for i in iq]
            d.qvel[:] = [float(r[i]) for i in iv]
            mujoco.mj_forward(m, d)
            c, s = np.cos(heading(d.qpos)), np.sin(heading(d.qpos))
            to_h = lambda v: np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1]])  # noqa: E731 (W -> H, x and y)
            truth.append(to_h(d.qvel[:3])[1])
            for name, b in feet.items():
                n = sum(1 for i in range(d.ncon) if d.contact[i].dist < 0 and
                        b in (m.geom_bodyid[d.contact[i].geom1], m.geom_bodyid[d.contact[i].geom2]))
                p = d.xpos[b] + d.xmat[b].reshape(3, 3) @ SOLE_F
                jacp = np.zeros((3, m.nv))
                mujoco.mj_jac(m, d, jacp, None, p, b)
                flat[name].append((n >= 3, *to_h(jacp @ d.qvel)))
    print(f"{args.probe}, {args.t0}-{args.t1} s: pelvis v_y {np.mean(truth):+.3f} m/s")
    for name, a in flat.items():
        a = np.array(a)
        on = a[:, 0] > 0.5
        print(f"  {name}: flat in {on.mean():.2f} of the ticks; the sole point there v_x {a[on, 1].mean():+.3f}, "
              f"v_y {a[on, 2].mean():+.3f} m/s")


if __name__ == "__main__":
    main()
