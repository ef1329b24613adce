#!/usr/bin/env python3
"""What the accelerometer samples the loop reads still get wrong (imu_lowpass/README.md, "What 5 ms leaves").

From a pmg_policy_sil --probe CSV (the specific force, gyro and IMU orientation each tick read, MuJoCo's truth) and
the run's per-tick seed CSV, per segment (last 60 %), in the heading frame H:
  - the velocity estimator's prediction, mean of dv_H/dt = R_HB f_B - g e_z - w_z e_z x v_H with v_H the truth: over
    a steady walk it should be the truth's own mean dv_H/dt, about 0; the difference is a bias the estimator
    integrates whenever its gate rejects the legs;
  - the lever arm's part of it (w x (w x r), the IMU site 4.5 cm ahead of and 8.3 cm below the pelvis origin);
  - the mean vertical specific force in W (9.81 when unbiased);
  - the estimate against the truth (seed CSV: vx_est, vy_est against vx, vy), and the leg samples accepted.
Usage: python3 imu_bias.py OUT/probe.csv OUT/seedK.csv SEGMENT [SEGMENT ...]
"""
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../.."))  # training/
from probe_sil import quat_to_rot, read_probe  # noqa: E402

R_IMU = np.array([0.04525, 0.0, -0.08339])  # imu_in_pelvis in the pelvis frame [m] (config/robots/g1/*.xml)


def heading(R_WB):
    yaw = np.arctan2(R_WB[1, 0], R_WB[0, 0])
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def main():
    if len(sys.argv) < 4:
        raise SystemExit(__doc__)
    cols = read_probe(sys.argv[1])
    rows = list(csv.DictReader(open(sys.argv[2])))
    n = min(len(cols["t"]), len(rows))
    for seg in sys.argv[3:]:
        idx = [k for k in range(n) if rows[k]["segment"] == seg]
        if not idx:
            raise SystemExit(f"{sys.argv[2]}: no segment {seg}")
        idx = idx[int(0.4 * len(idx)):]
        pred, lever, f_z, v_true = [], [], [], []
        for k in idx:
            R_WB = quat_to_rot([cols[c][k] for c in ("imu_qw", "imu_qx", "imu_qy", "imu_qz")])
            R_HW = heading(R_WB)
            R_HB = R_HW @ R_WB
            f_B = np.array([cols["acc_x"][k], cols["acc_y"][k], cols["acc_z"][k]])
            a_H = R_HB @ f_B - np.array([0, 0, 9.81])
            w_z = (R_HB @ np.array([cols["gyro_x"][k], cols["gyro_y"][k], cols["gyro_z"][k]]))[2]
            v = R_HW @ np.array([cols["qvel0"][k], cols["qvel1"][k], cols["qvel2"][k]])
            pred.append([a_H[0] + w_z * v[1], a_H[1] - w_z * v[0]])
            f_z.append((R_WB @ f_B)[2])
            v_true.append(v[:2])
            R_true = quat_to_rot([cols[f"qpos{i}"][k] for i in (3, 4, 5, 6)])
            w_B = np.array([cols["qvel3"][k], cols["qvel4"][k], cols["qvel5"][k]])
            lever.append((heading(R_true) @ R_true @ np.cross(w_B, np.cross(w_B, R_IMU)))[:2])
        v_true = np.array(v_true)
        T = cols["t"][idx[-1]] - cols["t"][idx[0]]
        dv = (v_true[-20:].mean(axis=0) - v_true[:20].mean(axis=0)) / T
        p, lv = np.mean(pred, axis=0), np.mean(lever, axis=0)
        w = [rows[k] for k in idx]
        m = lambda c: np.mean([float(r[c]) for r in w])  # noqa: E731
        acc = sum(1 for r in w if float(r["leg_rejected"]) == 0)
        print(f"{seg}: predicted dv/dt ({p[0]:+.3f}, {p[1]:+.3f}) m/s^2 against the truth's ({dv[0]:+.3f}, {dv[1]:+.3f}),"
              f" lever arm ({lv[0]:+.3f}, {lv[1]:+.3f}); vertical specific force {np.mean(f_z):.3f};"
              f" estimate - truth ({m('vx_est') - m('vx'):+.3f}, {m('vy_est') - m('vy'):+.3f}) m/s;"
              f" leg samples accepted {acc}/{len(w)}")


if __name__ == "__main__":
    main()
