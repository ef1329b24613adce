#!/usr/bin/env python3
"""The training model's leg-against-leg contacts against the SIL's (ctest training_leg_collisions).

Usage: test_leg_collisions.py [--poses 4000] [--seed 0]
Runs in the training environment (.venv-training, like test_smoke_cpu.py: it re-runs itself with
that interpreter; PMG_SKIP_TRAINING_TESTS=1 skips, exit 77). Plain MuJoCo, no JAX compile.

Why: policies trained on 8 foot spheres alone fell in the SIL while side-stepping, one shin hooked
behind the other (docs/policy.md, "Why it fell"): the SIL's collision meshes have those contacts and
training did not. g1_env.mjx_friendly_mjcf now keeps capsules fitted to the thigh, shin and foot of
each side and the pairs LEG_COLLISION_PAIRS. Checks:
1. the training model has exactly those pairs, and none with leg_collisions=False;
2. the standing pose leaves every pair at least 5 cm apart (no contact the robot does not have);
3. on random leg poses around the gait (hip roll and yaw reaching into the other leg), every pose
   whose SIL collision meshes penetrate by more than 1 mm is a contact of the capsules too (the
   training model misses no contact the SIL has), and the capsules touch in at most 10 % of the
   poses whose meshes are more than 1 cm apart (they err on the side of contact, not much);
4. every pair matters: each one is in contact on some of those poses.
Prints one line per check; exit 0 iff all pass.
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from test_smoke_cpu import CHILD, Checks, relaunch  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--poses", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    import mujoco
    import numpy as np
    sys.path.insert(0, os.path.join(REPO, "training"))
    from pmg_train.g1_env import LEG_COLLISION_PAIRS, mjx_friendly_mjcf

    mjcf = os.path.join(REPO, "config/robots/g1/g1_29dof_rev_1_0.xml")
    check = Checks()
    sil = mujoco.MjModel.from_xml_path(mjcf)
    train = mujoco.MjModel.from_xml_string(mjx_friendly_mjcf(mjcf))
    bare = mujoco.MjModel.from_xml_string(mjx_friendly_mjcf(mjcf, leg_collisions=False))
    names = {frozenset((train.geom(int(a)).name, train.geom(int(b)).name))
             for a, b in zip(train.pair_geom1, train.pair_geom2)}
    check(names == {frozenset(p) for p in LEG_COLLISION_PAIRS} and train.npair == len(LEG_COLLISION_PAIRS)
          and bare.npair == 0,
          f"training model pairs {sorted(tuple(sorted(p)) for p in names)}; {bare.npair} without leg collisions")

    def leg_qpos(m):
        return [m.jnt_qposadr[j] for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE][:12]

    def pose(m, d, q):
        d.qpos[:] = m.qpos0
        d.qpos[2] = 1.5
        for k, a in enumerate(leg_qpos(m)):
            d.qpos[a] = q[k]
        mujoco.mj_forward(m, d)

    ds, dt = mujoco.MjData(sil), mujoco.MjData(train)
    leg = [g for g in range(sil.ngeom) if (sil.geom_contype[g] or sil.geom_conaffinity[g])
           and any(k in sil.body(int(sil.geom_bodyid[g])).name for k in ("hip", "knee", "ankle"))]
    left = [g for g in leg if sil.body(int(sil.geom_bodyid[g])).name.startswith("left")]
    right = [g for g in leg if sil.body(int(sil.geom_bodyid[g])).name.startswith("right")]
    pairs = [(train.geom(a).id, train.geom(b).id) for a, b in LEG_COLLISION_PAIRS]
    ft = np.zeros(6)

    def distances(q, distmax=0.05):
        pose(sil, ds, q)
        pose(train, dt, q)
        mesh = min(mujoco.mj_geomDistance(sil, ds, a, b, distmax, ft) for a in left for b in right)
        caps = [mujoco.mj_geomDistance(train, dt, a, b, distmax, ft) for a, b in pairs]
        return mesh, caps

    _, stand = distances(np.zeros(12), distmax=1.0)
    check(min(stand) >= 0.05, f"standing: capsule pairs {np.round(stand, 3).tolist()} m apart (>= 0.05)")

    # Leg order per side: hip pitch, roll, yaw, knee, ankle pitch, roll (config/robots/g1/g1.yaml).
    rng = np.random.default_rng(args.seed)
    lo = np.array([-0.8, -0.35, -0.5, 0.0, -0.6, -0.2])
    hi = np.array([0.5, 0.15, 0.5, 1.4, 0.3, 0.2])
    mesh_d, caps_d = [], []
    for _ in range(args.poses):
        ql = rng.uniform(lo, hi)
        qr = rng.uniform(lo, hi) * np.array([1, -1, -1, 1, 1, -1])  # mirrored ranges (roll, yaw sign)
        mesh, caps = distances(np.concatenate([ql, qr]))
        mesh_d.append(mesh)
        caps_d.append(caps)
    mesh_d, caps_d = np.array(mesh_d), np.array(caps_d)
    hit = mesh_d < -1e-3
    far = mesh_d > 1e-2
    caught = (caps_d[hit].min(1) <= 0).sum() if hit.any() else 0
    false_pos = (caps_d[far].min(1) <= 0).mean() if far.any() else 1.0
    check(hit.sum() >= 20, f"{hit.sum()} of {args.poses} random poses have SIL leg meshes penetrating (>= 20 to judge)")
    check(caught == hit.sum(), f"capsules touch in {caught} of those {hit.sum()} poses (all)")
    check(false_pos <= 0.10, f"capsules touch in {100 * false_pos:.1f} % of the {far.sum()} poses whose meshes "
                             f"are > 1 cm apart (<= 10 %)")
    per_pair = (caps_d[hit] <= 0).sum(0)
    check(all(n > 0 for n in per_pair),
          "contacts per pair on the penetrating poses: " +
          ", ".join(f"{a}/{b} {n}" for (a, b), n in zip(LEG_COLLISION_PAIRS, per_pair)))
    print(f"{check.passed} passed, {check.failed} failed")
    return 0 if check.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
