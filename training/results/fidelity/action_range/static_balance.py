#!/usr/bin/env python3
"""How low can the G1 stand with its torso upright, feet flat, and its centre of mass over its feet?

A static question, asked of the model the SIL runs (config/robots/g1/g1_29dof_rev_1_0.xml): for each pelvis
height, search the symmetric sagittal stances (ankle pitch a, knee k, pelvis pitch p; hip pitch chosen so that each
sole is level, waist pitch -p so that the torso is upright, every other joint at its default in
config/robots/g1/g1.yaml) and report the largest margin by which the whole-body centre of mass (CoM) lies inside the
soles' contact spheres along x (heel at -0.05 m, toe at +0.12 m from the ankle roll link, frame W). A stance is
admissible when every joint is inside its MJCF range.

Usage (from the checkout):
  .venv-training/bin/python training/results/fidelity/action_range/static_balance.py \
      [--torso-pitch RAD] [--out CSV]

Prints, per pelvis height [m], among the stances with the pelvis within 0.05 rad of level: the best CoM margin [m]
(positive: inside the support; the smaller of the toe and heel distances; 0.085 is the CoM centred) with its joint
angles [rad], and with --reach TRAIN_CONFIG the best margin among the stances whose hip pitch, knee and ankle pitch
lie inside that actor's reach (action_range.py: standing pose +- action_scale; before any PD sag).
"""
import argparse
import math
import os
import sys

import mujoco
import numpy as np
import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4))


def load():
    model = mujoco.MjModel.from_xml_path(os.path.join(ROOT, "config/robots/g1/g1_29dof_rev_1_0.xml"))
    with open(os.path.join(ROOT, "config/robots/g1/g1.yaml")) as f:
        robot = yaml.safe_load(f)
    defaults = {j["name"]: float(j.get("default", 0.0)) for j in robot["joints"]}
    return model, defaults


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--torso-pitch", type=float, default=0.0, help="torso pitch in W [rad], forward positive")
    ap.add_argument("--reach", default=None, metavar="TRAIN_CONFIG", help="an actor's train_config.json (action_scale)")
    ap.add_argument("--out", default=None, help="CSV of every admissible stance (height, margin, a, k, hip, p)")
    args = ap.parse_args()
    model, defaults = load()
    data = mujoco.MjData(model)
    jid = {model.joint(i).name: i for i in range(model.njnt)}
    qadr = {n: model.jnt_qposadr[i] for n, i in jid.items()}
    rng = {n: model.jnt_range[i] for n, i in jid.items()}
    feet = [model.body("left_ankle_roll_link").id, model.body("right_ankle_roll_link").id]
    heel_x, toe_x, sole_z = -0.05, 0.12, -0.03 - 0.005

    rows = []
    for a in np.arange(-0.8727, 0.0, 0.01):
        for k in np.arange(0.0, 2.2, 0.02):
            for p in np.arange(-0.1, 0.55, 0.025):
                hip = -(a + k + p)
                waist = args.torso_pitch - p
                q = {f"{s}_ankle_pitch_joint": a for s in ("left", "right")}
                q.update({f"{s}_knee_joint": k for s in ("left", "right")})
                q.update({f"{s}_hip_pitch_joint": hip for s in ("left", "right")})
                q["waist_pitch_joint"] = waist
                if any(not (rng[n][0] - 1e-9 <= v <= rng[n][1] + 1e-9) for n, v in q.items()):
                    continue
                qpos = np.zeros(model.nq)
                qpos[3:7] = [math.cos(p / 2), 0.0, math.sin(p / 2), 0.0]  # pelvis pitch p about y (forward positive)
                for n, v in defaults.items():
                    qpos[qadr[n]] = v
                for n, v in q.items():
                    qpos[qadr[n]] = v
                data.qpos[:] = qpos
                mujoco.mj_kinematics(model, data)
                mujoco.mj_comPos(model, data)
                # soles: the contact spheres' lowest points, in W
                R = data.xmat[feet[0]].reshape(3, 3)
                sole_pts = []
                for b in feet:
                    Rb = data.xmat[b].reshape(3, 3)
                    for x in (heel_x, toe_x):
                        sole_pts.append(data.xpos[b] + Rb @ np.array([x, 0.0, sole_z]))
                sole_pts = np.array(sole_pts)
                height = data.xpos[model.body("pelvis").id][2] - sole_pts[:, 2].min()
                com = data.subtree_com[0]
                xs = sole_pts[:, 0]
                margin = min(com[0] - xs.min(), xs.max() - com[0])
                tilt = abs(math.asin(max(-1.0, min(1.0, -R[2, 0]))))
                if tilt > 0.01:
                    continue
                rows.append((height, margin, a, k, hip, p))
    rows = np.array(rows)
    reach = None
    if args.reach:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from action_range import leg_range
        lo, hi = leg_range(args.reach)
        reach = ((rows[:, 2] >= lo[4]) & (rows[:, 2] <= hi[4]) & (rows[:, 3] >= lo[3]) & (rows[:, 3] <= hi[3])
                 & (rows[:, 4] >= lo[0]) & (rows[:, 4] <= hi[0]))
    if args.out:
        np.savetxt(args.out, rows, delimiter=",", header="height,margin,ankle,knee,hip,pelvis_pitch", comments="",
                   fmt="%.5f")
    print(f"torso pitch {args.torso_pitch:+.3f} rad; {len(rows)} admissible stances")
    print(" height | best CoM margin [m]  ankle   knee    hip  pelvis pitch | within the reach: margin  ankle   knee    hip")
    level = np.abs(rows[:, 5]) <= 0.05
    for h in np.arange(0.60, 0.705, 0.01):
        near = (np.abs(rows[:, 0] - h) < 0.0025) & level
        if not near.any():
            print(f"  {h:.2f}  | none")
            continue
        b = rows[near][np.argmax(rows[near][:, 1])]
        line = f"  {h:.2f}  | {b[1]:+.3f}             {b[2]:+.3f} {b[3]:+.3f} {b[4]:+.3f} {b[5]:+.3f}        |"
        if reach is not None:
            ok = near & reach
            if ok.any():
                r = rows[ok][np.argmax(rows[ok][:, 1])]
                line += f" {r[1]:+.3f}  {r[2]:+.3f} {r[3]:+.3f} {r[4]:+.3f}"
            else:
                line += " none"
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
