#!/usr/bin/env python3
"""The SIL against the actor's training environment, tick by tick (ctest training_sil_probe).

Usage: test_sil_probe.py PMG_POLICY_SIL [--workdir DIR]
Runs in the training environment (.venv-training, like test_smoke_cpu.py: it re-runs itself with
that interpreter; PMG_SKIP_TRAINING_TESTS=1 skips, exit 77). Plain MuJoCo and NumPy, no JAX compile.

Why: for weeks the SIL walked 20-40 % slower than every actor's own environment and fell at 1 m/s,
and nothing said why. The cause was the HAL supervisor's slew limit on commanded positions (then
20 rad/s), which the environment does not have (training/README.md "The HAL's slew limit"). This test
runs V20b (training/results/fidelity/fast20_gamma97) walking forward in the SIL with
`pmg_policy_sil --probe --q-rate-max 600` (the HAL's default; features off, no noise) and compares with
training/probe_sil.py:
1. the runner: the actor (actor.npz, NumPy) on the SIL's observations gives the SIL's actions (1e-5);
2. the observation: the SIL's joint velocities and default pose are the environment's (1e-5 rad/s,
   1e-6 rad), its projected gravity within 0.005, its gyro within 20 % of the signal (the IMU sensor
   lags MuJoCo's state by one 1 ms physics step);
3. the physics: MuJoCo 3.17 on the environment's model, stepped one control period from each logged
   state with the logged motor commands, lands within 10 % (rms) of the SIL's next leg joint velocities;
4. the hidden effect: with the old slew (`--q-rate-max 20`) the probe reports the slew in most
   periods, the physics comparison misses by more than 25 % in them, and by less than half as much in
   the periods without it: the tool finds the effect and where it acts.
Prints one line per check; exit 0 iff all pass.
"""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from test_smoke_cpu import CHILD, Checks, relaunch  # noqa: E402

RUN = "training/results/fidelity/fast20_gamma97"
OFF = ["--velocity-feedback", "off", "--upset-guard", "off", "--feedforward", "off", "--posture-feedback", "off",
       "--joint-stops", "off", "--walking-height-floor", "off", "--braking", "off", "--noise", "false"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sil", help="build/bin/pmg_policy_sil")
    ap.add_argument("--workdir", default=None)
    args = ap.parse_args()
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    sys.path.insert(0, os.path.join(REPO, "training"))
    os.chdir(REPO)
    from probe_sil import probe
    work = args.workdir or tempfile.mkdtemp(prefix="pmg_sil_probe_")
    os.makedirs(work, exist_ok=True)
    check = Checks()

    def run(tag, extra):
        csv = os.path.join(work, f"probe_{tag}.csv")
        cmd = [args.sil, "--model", f"{RUN}/g1_pmg_policy.onnx", "--commands", "config/policies/eval_walk_short.yaml",
               "--seeds", "1", "--out", os.path.join(work, tag), "--probe", csv] + OFF + extra
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout[-2000:], r.stderr[-2000:])
            raise SystemExit(f"FAIL {' '.join(cmd)}: exit {r.returncode}")
        return probe(csv, f"{RUN}/actor.npz")

    r = run("slew600", ["--q-rate-max", "600"])
    a = r["runner"]["action"]
    check(a["rms"] < 1e-5 and a["signal_rms"] > 0.1,
          f"runner: actor.npz on the SIL's observations gives its actions, rms {a['rms']:.1e} (actions rms {a['signal_rms']:.2f})")
    o = r["observation"]
    q0 = max(abs(x - y) for x, y in zip(o["implied q_default (mean)"], o["env q_default"]))
    check(o["joint_vel"]["rms"] < 1e-5 and q0 < 1e-6 and o["implied q_default spread [rad]"] < 1e-6,
          f"observation: joint velocities rms {o['joint_vel']['rms']:.1e} rad/s, default pose {q0:.1e} rad")
    check(o["projected_gravity_B"]["rms"] < 0.005 and o["base_ang_vel_B"]["rms"] < 0.2 * o["base_ang_vel_B"]["signal_rms"],
          f"observation: projected gravity rms {o['projected_gravity_B']['rms']:.4f}, gyro rms "
          f"{o['base_ang_vel_B']['rms']:.3f} of {o['base_ang_vel_B']['signal_rms']:.3f} rad/s")
    p = r["physics"][0]
    qd = p["leg_qd [rad/s]"]
    check(qd["rms"] < 0.1 * qd["signal_rms"] and r["hal_slew"]["periods with a slew-limited joint"] < 0.01,
          f"physics ({p['label']}): next leg qd rms {qd['rms']:.3f} of {qd['signal_rms']:.3f} rad/s a period; "
          f"slew-limited periods {r['hal_slew']['periods with a slew-limited joint']:.3f}")

    # The specific force the ticks read (the probe's last columns, after the HAL's low-pass), rotated into W by the
    # orientation they read: gravity's reaction, +9.81 m/s^2 up, on average over the run (the pelvis ends where it
    # started in height), and no horizontal mean beyond the walk's own accelerations.
    import numpy as np  # after relaunch(): the training environment's
    from probe_sil import quat_to_rot, read_probe
    cols = read_probe(os.path.join(work, "probe_slew600.csv"))
    acc = np.stack([cols["acc_x"], cols["acc_y"], cols["acc_z"]], axis=1)
    quat = np.stack([cols["imu_qw"], cols["imu_qx"], cols["imu_qy"], cols["imu_qz"]], axis=1)
    f_w = np.array([quat_to_rot(q) @ a for q, a in zip(quat, acc)]).mean(axis=0)
    check(abs(f_w[2] - 9.81) < 0.3 and np.hypot(f_w[0], f_w[1]) < 0.3,
          f"specific force in W, mean over the run: ({f_w[0]:+.3f}, {f_w[1]:+.3f}, {f_w[2]:.3f}) m/s^2")

    s = run("slew20", ["--q-rate-max", "20"])
    ps = s["physics"][0]
    share = s["hal_slew"]["periods with a slew-limited joint"]
    held, free = ps["leg_qd rms, periods the HAL slew acted in [rad/s]"], ps["leg_qd rms, periods it did not [rad/s]"]
    sig = ps["leg_qd [rad/s]"]["signal_rms"]
    check(share > 0.5 and held is not None and held > 0.25 * sig and (free is None or free < 0.5 * held),
          f"hidden slew (--q-rate-max 20): reported in {share:.0%} of periods; the physics misses by {held:.3f} rad/s "
          f"there ({held / sig:.0%} of the signal), {free if free is not None else float('nan'):.3f} elsewhere")
    print(f"{check.passed} passed, {check.failed} failed")
    sys.exit(1 if check.failed else 0)


if __name__ == "__main__":
    main()
