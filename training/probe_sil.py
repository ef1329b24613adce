#!/usr/bin/env python3
"""Sim-to-sim probe: where does the SIL (pmg_policy_sil, MuJoCo 2.2.2) part from the actor's training
environment (MJX / MuJoCo 3.17)?

Reads the per-tick probe of `pmg_policy_sil --probe FILE` (MuJoCo's qpos/qvel when the tick read its state,
the state it read, the actor's observation and action, the motor commands it wrote) and makes three
comparisons on the same ticks (active mode only):

1. runner:      the actor (actor.npz, numpy) on the SIL's observations against the SIL's actions;
2. observation: the observation terms the environment builds from MuJoCo's state (G1PmgEnv.raw_obs: the
                pelvis quaternion and body-frame angular velocity, the leg joints) against the SIL's
                (from the IMU sensors and the encoders);
3. physics:     MuJoCo 3.17 (this Python's) stepped one control period from each logged state with the
                logged motor commands (explicit PD at the SIL's 1 ms, torque limits) against the SIL's
                next logged state: on the environment's own model (env.mj_model) and on the SIL's MJCF.

Prints one table per comparison (per-term / per-joint RMS and max differences) and writes them as JSON.
Needs the training environment (.venv-training).

    build/bin/pmg_policy_sil --model RUN/g1_pmg_policy.onnx --seeds 1 --noise false --probe /tmp/p.csv ...
    python3 training/probe_sil.py /tmp/p.csv RUN/actor.npz --out /tmp/probe.json
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def read_probe(path):
    """Columns of a probe CSV as float arrays (mode as strings); raises SystemExit naming the file."""
    try:
        with open(path) as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise SystemExit(f"{path}: cannot read ({e})")
    if len(rows) < 3 or rows[0][0] != "t":
        raise SystemExit(f"{path}: not a pmg_policy_sil --probe CSV (expected a header starting with 't' and rows)")
    head = rows[0]
    body = [r for r in rows[1:] if len(r) == len(head)]
    cols = {}
    for i, name in enumerate(head):
        vals = [r[i] for r in body]
        if name == "mode":
            cols[name] = np.array(vals)
        else:
            try:
                cols[name] = np.array([float(v) for v in vals])
            except ValueError:
                raise SystemExit(f"{path}: column {name}: non-numeric value")
    return cols


def block(cols, prefix):
    keys = []
    i = 0
    while f"{prefix}{i}" in cols:
        keys.append(f"{prefix}{i}")
        i += 1
    return np.stack([cols[k] for k in keys], axis=1) if keys else np.zeros((len(cols["t"]), 0))


def quat_to_rot(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def stats(diff, scale=None):
    d = np.asarray(diff, float)
    out = {"rms": float(np.sqrt(np.mean(d ** 2))), "max": float(np.max(np.abs(d)))}
    if scale is not None:
        out["signal_rms"] = float(np.sqrt(np.mean(np.asarray(scale, float) ** 2)))
    return out


def sil_mjcf_text(path, timestep=0.001, armature=0.01, damping=0.05, frictionloss=0.2, imu_site="imu_in_pelvis"):
    """The MJCF text the SIL compiles (src/common/mujoco_model.cpp, adaptMjcfForMujoco22, with
    Mujoco22Options' defaults): absolute meshdir, autolimits, the timestep, default joint armature, damping
    and frictionloss (MuJoCo's default class: the free joint takes them too), the IMU's framequat."""
    import re
    with open(path) as f:
        xml = f.read()
    xml = re.sub(r'\s+actuatorfrc(range|limited)="[^"]*"', "", xml)
    d = os.path.dirname(os.path.abspath(path))
    m = re.search(r'<compiler([^>]*?)/?>', xml)
    attrs = m.group(1)
    md = re.search(r'meshdir="([^"]*)"', attrs)
    meshdir = os.path.normpath(os.path.join(d, md.group(1))) if md else d
    attrs = re.sub(r'\s*autolimits="[^"]*"', "", re.sub(r'\s*meshdir="[^"]*"', "", attrs))
    head = (f'<compiler{attrs} meshdir="{meshdir}" autolimits="true"/>\n<option timestep="{timestep}"/>\n'
            f'<default><joint armature="{armature}" damping="{damping}" frictionloss="{frictionloss}"/></default>')
    xml = xml[:m.start()] + head + xml[m.end():]
    quat = f'<framequat name="{imu_site}-orientation" objtype="site" objname="{imu_site}"/>'
    i = xml.find("<sensor>")
    return xml[:i + 8] + quat + xml[i + 8:] if i >= 0 else xml.replace("</mujoco>", f"<sensor>{quat}</sensor></mujoco>")


def actor_numpy(npz, obs):
    h = (obs - npz["obs_mean"]) / npz["obs_std"]
    i = 0
    while f"w{i}" in npz:
        h = h @ npz[f"w{i}"] + npz[f"b{i}"]
        if f"w{i + 1}" in npz:
            h = h * (1.0 / (1.0 + np.exp(-h)))
        i += 1
    return np.tanh(h[..., :12])


def physics_compare(model, qpos, qvel, cmd, active, substeps, slew=None, leg=12, label=""):
    """One control period of MuJoCo (this Python's) from each logged state with the logged commands."""
    import mujoco
    m = model
    d = mujoco.MjData(m)
    nj = cmd["q"].shape[1]
    tau_max = np.array([m.actuator_ctrlrange[i, 1] if m.actuator_ctrllimited[i] else np.inf for i in range(m.nu)])
    dq, dv, dvb, held = [], [], [], []
    for k in range(len(qpos) - 1):
        if not (active[k] and active[k + 1]):
            continue
        held.append(slew is not None and slew[k + 1] > 0)
        d.qpos[:], d.qvel[:] = qpos[k], qvel[k]
        d.qacc_warmstart[:] = 0
        mujoco.mj_forward(m, d)
        for _ in range(substeps):
            q, v = d.qpos[7:7 + nj], d.qvel[6:6 + nj]
            tau = cmd["kp"][k] * (cmd["q"][k] - q) + cmd["kd"][k] * (cmd["qd"][k] - v) + cmd["tau"][k]
            d.ctrl[:nj] = np.clip(tau, -tau_max[:nj], tau_max[:nj])
            mujoco.mj_step(m, d)
        dq.append(d.qpos[7:7 + leg] - qpos[k + 1][7:7 + leg])
        dv.append(d.qvel[6:6 + leg] - qvel[k + 1][6:6 + leg])
        dvb.append(d.qvel[:6] - qvel[k + 1][:6])
    dq, dv, dvb, held = np.array(dq), np.array(dv), np.array(dvb), np.array(held, bool)
    # the same against doing nothing: how much one period moves the state (the scale of the differences)
    moved_v = np.array([qvel[k + 1][6:6 + leg] - qvel[k][6:6 + leg] for k in range(len(qpos) - 1)
                        if active[k] and active[k + 1]])
    moved_b = np.array([qvel[k + 1][:6] - qvel[k][:6] for k in range(len(qpos) - 1) if active[k] and active[k + 1]])
    return {"label": label, "ticks": int(len(dq)),
            "leg_q [rad]": stats(dq), "leg_qd [rad/s]": stats(dv, moved_v),
            "base_lin_vel [m/s]": stats(dvb[:, :3], moved_b[:, :3]),
            "base_ang_vel [rad/s]": stats(dvb[:, 3:], moved_b[:, 3:]),
            "mean base_lin_vel diff (x, y, z) [m/s]": [float(x) for x in dvb[:, :3].mean(axis=0)],
            "per-joint leg_qd rms [rad/s]": [float(x) for x in np.sqrt((dv ** 2).mean(axis=0))],
            "per-joint leg_qd mean [rad/s]": [float(x) for x in dv.mean(axis=0)],
            # the periods in which the HAL's slew limit held a command back (the motors got other set-points
            # than the logged ones) against the others
            "leg_qd rms, periods the HAL slew acted in [rad/s]": float(np.sqrt((dv[held] ** 2).mean())) if held.any() else None,
            "leg_qd rms, periods it did not [rad/s]": float(np.sqrt((dv[~held] ** 2).mean())) if (~held).any() else None,
            "periods the HAL slew acted in": int(held.sum())}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("probe", help="pmg_policy_sil --probe CSV")
    ap.add_argument("actor", help="the actor's actor.npz (beside it: train_config.json)")
    ap.add_argument("--out", default=None, help="JSON of the results")
    ap.add_argument("--sil-mjcf", default="config/robots/g1/g1_29dof_rev_1_0.xml",
                    help="the SIL's MJCF (the robot config's mjcf_path) for the third comparison")
    ap.add_argument("--substeps", type=int, default=10, help="physics steps per control period (SIL: 10 of 1 ms)")
    ap.add_argument("--skip-physics", action="store_true")
    args = ap.parse_args(argv)
    res = probe(args.probe, args.actor, args.sil_mjcf, args.substeps, not args.skip_physics)
    text = json.dumps(res, indent=1)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")


def probe(probe_csv, actor, sil_mjcf="config/robots/g1/g1_29dof_rev_1_0.xml", substeps=10, physics=True):
    """The three comparisons (module docstring) as a dict; SystemExit naming the file on bad input."""
    sil_mjcf = os.path.abspath(sil_mjcf)
    cols = read_probe(probe_csv)
    npz = np.load(actor)
    active = cols["mode"] == "active"
    if active.sum() < 2:
        raise SystemExit(f"{probe_csv}: fewer than 2 ticks in mode active")
    obs, act = block(cols, "obs"), block(cols, "action")
    qpos, qvel = block(cols, "qpos"), block(cols, "qvel")
    res = {"probe": probe_csv, "actor": actor, "ticks_active": int(active.sum())}
    slew = cols.get("hal_slew")
    if slew is not None:  # joint-cycles the HAL's slew limit held back in the period before each row
        res["hal_slew"] = {"periods with a slew-limited joint": float(np.mean(slew[active] > 0)),
                           "slew-limited joint-cycles per period (mean)": float(np.mean(slew[active]))}

    # 1. runner
    a_np = actor_numpy(npz, obs[active].astype(np.float64))
    res["runner"] = {"action": stats(a_np - act[active], act[active])}

    # 2. observation terms from MuJoCo's state, as G1PmgEnv.raw_obs builds them
    from pmg_train.g1_env import OBS_TERMS, LEG
    offs, o = {}, 0
    for name, size, scale in OBS_TERMS:
        offs[name] = (o, size, np.broadcast_to(np.asarray(scale, float), (size,)))
        o += size
    sil_raw = {n: obs[:, a:a + s] / sc for n, (a, s, sc) in offs.items()}
    grav = np.array([quat_to_rot(q).T @ np.array([0, 0, -1.0]) for q in qpos[:, 3:7]])
    env_terms = {"base_ang_vel_B": qvel[:, 3:6], "projected_gravity_B": grav,
                 "joint_vel": qvel[:, 6:6 + LEG]}
    # joint_pos_rel: q - q_default; the default from the SIL's own term at the first active tick (the
    # environment's q_default is compared separately below)
    obs_res = {}
    for n, ref in env_terms.items():
        obs_res[n] = stats(sil_raw[n][active] - ref[active], ref[active])
    q_default_sil = (qpos[:, 7:7 + LEG] - sil_raw["joint_pos_rel"])[active]
    obs_res["implied q_default spread [rad]"] = float(np.max(np.ptp(q_default_sil, axis=0)))
    prev = np.vstack([np.zeros((1, LEG)), act[:-1]])
    obs_res["last_action vs previous tick's action"] = stats((sil_raw["last_action"] - prev)[active][1:])
    res["observation"] = obs_res
    res["observation"]["implied q_default (mean)"] = [float(x) for x in q_default_sil.mean(axis=0)]

    # 3. physics
    if physics:
        import mujoco
        from eval_mjx import env_from_train_config
        from pmg_train.g1_env import EnvConfig, G1PmgEnv
        from pmg_train.paths import repo_root
        cmd = {k: block(cols, f"cmd_{k}") for k in ("q", "qd", "kp", "kd", "tau")}
        tc = os.path.join(os.path.dirname(os.path.abspath(actor)), "train_config.json")
        cwd = os.getcwd()
        os.chdir(repo_root(None))
        trained = env_from_train_config(tc if os.path.exists(tc) else None)
        env = G1PmgEnv(EnvConfig(**{**trained, "pd_damping": "explicit", "sim_dt": 0.001}))
        res["observation"]["env q_default"] = [float(x) for x in env.q_default[:LEG]]
        phys = []
        m_env = env.mj_model
        phys.append(physics_compare(m_env, qpos, qvel, cmd, active, substeps, slew, label="env model, MuJoCo "
                                    + mujoco.__version__))
        m_sil = mujoco.MjModel.from_xml_string(sil_mjcf_text(sil_mjcf))
        phys.append(physics_compare(m_sil, qpos, qvel, cmd, active, substeps, slew, label="SIL MJCF, MuJoCo "
                                    + mujoco.__version__))
        res["physics"] = phys
        os.chdir(cwd)
    return res


if __name__ == "__main__":
    main()
