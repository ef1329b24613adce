#!/usr/bin/env python3
"""The leg action scale's rules (EnvConfig.action_scale_rule; train_pmg.py --action-scale):
training/pmg_train/g1_env.py motion_action_scale and posture_action_scale.

  python3 training/tests/test_action_scale.py

Checks, on the shipped clips (config/clips/g1_walking_height; no physics, no env step compiled; seconds):
- The "motion" rule looks at the walking clips only: at the squat's rows below 0.66 m the PMG reference (the standing
  pose plus the row's offset, PMG eq. 10) lies outside the targets its scale can command (hip pitch, knee or ankle
  pitch beyond q_stand +- scale): the cause of the 0.62 m stand at 0.641 (training/results/fidelity/action_range/).
- The "posture" rule covers them: every squat row and both ends of the height range 0.59..0.78 m, every bend row in
  pitch -0.1..0.5 rad and every lean row in roll -0.2..0.2 rad lie inside q_stand +- scale on every leg joint.
- It is never below the motion rule, left/right symmetric, within [0.25, 2.0], and follows the range: with heights
  0.70..0.78 m its knee scale is smaller than with 0.59..0.78 m.
- rescale_actor.py carries H10a's actor to the posture scale: the rule's scale, the targets of small actions
  (|a| < 0.3) within 0.02 rad, the last_action normaliser times old/new scale, nothing else changed before the
  last layer; --action-scale factor --factor knee=1.2 multiplies both knees' scale and nothing else.
- G1PmgEnv builds its scale by the rule from the config's ranges (--command-range), refuses an unknown rule naming
  EnvConfig.action_scale_rule, and train_pmg.py parses --action-scale posture.
It re-runs itself in the training environment (test_smoke_cpu.relaunch; exit 77 with PMG_SKIP_TRAINING_TESTS=1).
Exit 0 on success, 1 on a failed check.
"""
import glob
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))  # training/: pmg_train, train_pmg
from test_smoke_cpu import CHILD, relaunch  # noqa: E402

CLIPS = os.path.join(ROOT, "config/clips/g1_walking_height")
LEG = 12


def outside(pmg, js, scale, clip, value):
    """Leg joints whose reference (standing pose + the static clip's offset at value) lies outside q_stand +- scale."""
    from pmg_train import pmg_generator as pg
    offset = np.asarray(pg._interp_static(np, clip, value))[:LEG] - np.asarray(pg._interp_static(np, clip, clip.neutral))[:LEG]
    return [j for j in range(LEG) if abs(offset[j]) > scale[j] + 1e-9]


def main():
    if os.environ.get(CHILD) != "1":
        relaunch(__file__)
    from pmg_train import pmg_generator as pg
    from pmg_train.g1_env import EnvConfig, G1PmgEnv, motion_action_scale, posture_action_scale
    import train_pmg
    failures = []

    def check(ok, msg):
        if not ok:
            failures.append(msg)

    js = pg.joint_space_from_robot_yaml(os.path.join(ROOT, "config/robots/g1/g1.yaml"))
    pmg = pg.load_library(sorted(glob.glob(os.path.join(CLIPS, "*.yaml"))), js)
    squat, bend, lean = pmg.static[2], pmg.static[0], pmg.static[1]
    check(squat is not None and bend is not None and lean is not None, "the shipped set has squat, bend and lean")
    ranges = {0: (-0.1, 0.5), 1: (-0.2, 0.2), 2: (0.59, 0.78)}
    motion = motion_action_scale(pmg, js)
    posture = posture_action_scale(pmg, js, ranges)

    # The motion rule cannot command the deep crouch (hip pitch 0, knee 3, ankle pitch 4 of the left leg).
    for value in (0.59, 0.62, 0.64):
        bad = outside(pmg, js, motion, squat, value)
        check(3 in bad, f"motion rule: the squat at {value} m should need a knee beyond the reach (outside: {bad})")
    check(not outside(pmg, js, motion, squat, 0.74), "motion rule: the squat at 0.74 m lies inside the reach")

    # The posture rule covers every posture in the ranges.
    for clip, (lo, hi) in ((squat, ranges[2]), (bend, ranges[0]), (lean, ranges[1])):
        for value in [v for v in clip.values if lo <= v <= hi] + [lo, hi]:
            bad = outside(pmg, js, posture, clip, float(value))
            check(not bad, f"posture rule: {clip.name} at {value:.3f} outside the reach on joints {bad}")
    check(np.all(posture >= motion - 1e-12), f"posture rule below motion: {posture} vs {motion}")
    check(np.allclose(posture[:6], posture[6:]), f"posture rule not left/right symmetric: {posture}")
    check(np.all((posture >= 0.25) & (posture <= 2.0)), f"posture rule outside [0.25, 2.0]: {posture}")
    check(posture[3] > motion[3] + 0.3, f"posture rule: knee {posture[3]:.3f} not well beyond motion {motion[3]:.3f}")
    shallow = posture_action_scale(pmg, js, {0: ranges[0], 1: ranges[1], 2: (0.70, 0.78)})
    check(shallow[3] < posture[3] - 0.1, f"posture rule ignores the height range: knee {shallow[3]:.3f} vs {posture[3]:.3f}")

    # The env builds it from its config's ranges; an unknown rule is refused naming the field.
    env = G1PmgEnv(EnvConfig(clips=CLIPS, action_scale_rule="posture", pitch=ranges[0], roll=ranges[1],
                             height=ranges[2]))
    check(np.allclose(env.action_scale, posture, atol=1e-6), f"G1PmgEnv posture scale {env.action_scale} != {posture}")
    env = G1PmgEnv(EnvConfig(clips=CLIPS))
    check(np.allclose(env.action_scale, motion, atol=1e-6), f"G1PmgEnv default scale {env.action_scale} != {motion}")
    try:
        G1PmgEnv(EnvConfig(clips=CLIPS, action_scale_rule="widest"))
        failures.append("an unknown action_scale_rule was accepted")
    except ValueError as e:
        check("action_scale_rule" in str(e) and "posture" in str(e), f"unknown rule's error: {e}")
    check(train_pmg.parse_args(["--out", "/tmp/x", "--action-scale", "posture"]).action_scale == "posture",
          "--action-scale posture does not parse")

    # rescale_actor.py carries H10a's actor to the posture scale: the new scale is the rule's, small actions keep
    # their targets, the last_action normaliser follows the factor, and the rest of the actor is unchanged.
    import tempfile
    import rescale_actor
    src = os.path.join(ROOT, "training/results/fidelity/crouched_box/H10a/actor.npz")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "actor.npz")
        rescale_actor.main([src, "--action-scale", "posture", "--command-range", "height=0.59,0.78",
                            "--command-range", "pitch=-0.1,0.5", "--samples", "512", "--out", out])
        with np.load(src) as z:
            old = {k: z[k] for k in z.files}
        with np.load(out) as z:
            new = {k: z[k] for k in z.files}
    check(np.allclose(new["action_scale"], posture, atol=1e-6), f"rescaled actor's scale {new['action_scale']}")
    r = old["action_scale"] / new["action_scale"]
    check(np.allclose(new["obs_std"][rescale_actor.LAST_ACTION], old["obs_std"][rescale_actor.LAST_ACTION] * r,
                      rtol=1e-5), "last_action normaliser not scaled by old/new scale")
    check(np.array_equal(new["w0"], old["w0"]) and np.array_equal(new["obs_std"][:36], old["obs_std"][:36]),
          "rescale_actor changed more than the last layer and the last_action normaliser")
    rng = np.random.default_rng(1)
    obs = old["obs_mean"] + 0.3 * old["obs_std"] * rng.standard_normal((256, old["obs_mean"].shape[0]))
    a_old = rescale_actor.mean_action(old, obs)
    obs_new = obs.copy()
    obs_new[:, rescale_actor.LAST_ACTION] *= r
    a_new = rescale_actor.mean_action(new, obs_new)
    small = np.abs(a_old) < 0.3
    d = np.abs(a_new * new["action_scale"] - a_old * old["action_scale"])[small]
    check(small.sum() > 100 and d.max() < 0.02, f"small actions' targets moved by up to {d.max():.4f} rad")

    # --action-scale factor: the actor's own scale times the factor on the named joints of both legs.
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "actor.npz")
        rescale_actor.main([src, "--action-scale", "factor", "--factor", "knee=1.2", "--samples", "256", "--out", out])
        with np.load(out) as z:
            knee_only = z["action_scale"]
    want = old["action_scale"] * np.where(np.isin(np.arange(LEG), [3, 9]), 1.2, 1.0)
    check(np.allclose(knee_only, want, rtol=1e-6), f"--factor knee=1.2 gave {knee_only}, expected {want}")

    print(f"motion  scale (left leg) {np.round(motion[:6], 3)}")
    print(f"posture scale (left leg) {np.round(posture[:6], 3)}")
    for f in failures:
        print("FAIL:", f)
    print("ok" if not failures else f"{len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
