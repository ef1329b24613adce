#!/usr/bin/env python3
"""The symmetric-gait clip set (config/clips/g1_walking_height_symmetric, pmg_make_clips --symmetric-gaits)
gives mirror-symmetric references where the walking-height set does not (docs/motion.md "Symmetric gaits"),
measured by training/reference_symmetry.py's SideGap on the NumPy generator port, without GCO:
- walking forward (0.5, 1.0 m/s), backward (0.3 m/s) and crouched forward: q_ref(phase + 1/2, M u) equals
  M q_ref(phase, u) to 1e-9 rad RMS on the symmetric set, and differs by more than 0.02 on the
  walking-height set (the capture's left and right steps differ);
- a side-step and a turn in place, whose clips the option leaves alone, keep their side gap within 0.005
  rad. (Their references still change a little, up to 0.017 rad: the command-consistent blending gives
  the walking clips a small share of a pure side-step, and the consistency map is the new set's.)
Runs with the system python3 (NumPy, PyYAML)."""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "training"))
from pmg_train import pmg_generator as pg  # noqa: E402
from reference_symmetry import SideGap  # noqa: E402

js = pg.joint_space_from_robot_yaml(os.path.join(ROOT, "config", "robots", "g1", "g1.yaml"))
sets = {name: pg.load_library(os.path.join(ROOT, "config", "clips", name), js)
        for name in ("g1_walking_height", "g1_walking_height_symmetric")}
failures = []
for u_d, u_s in (((0.5, 0.0, 0.0), (0.0, 0.0, 0.0)), ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
                 ((-0.3, 0.0, 0.0), (0.0, 0.0, 0.0)), ((0.4, 0.0, 0.0), (0.0, 0.0, 0.68))):
    before = SideGap(sets["g1_walking_height"], js, u_d, u_s).rms()
    after = SideGap(sets["g1_walking_height_symmetric"], js, u_d, u_s).rms()
    print(f"u {u_d} {u_s}: RMS side gap {before:.4f} rad (walking height) -> {after:.2e} (symmetric gaits)")
    if not (after < 1e-9 and before > 0.02):
        failures.append(f"{u_d} {u_s}: side gap {before:.4f} -> {after:.2e}; expected > 0.02 -> < 1e-9")
for u_d in ((0.0, 0.3, 0.0), (0.0, 0.0, 0.5)):
    before = SideGap(sets["g1_walking_height"], js, u_d, (0.0, 0.0, 0.0)).rms()
    after = SideGap(sets["g1_walking_height_symmetric"], js, u_d, (0.0, 0.0, 0.0)).rms()
    print(f"u {u_d}: RMS side gap {before:.4f} rad (walking height) -> {after:.4f} (symmetric gaits)")
    if abs(after - before) > 0.005:
        failures.append(f"{u_d}: side gap {before:.4f} -> {after:.4f}; expected within 0.005 (clips left alone)")
print("\n".join("FAIL: " + f for f in failures) if failures else "reference symmetry: 6 cases as expected")
sys.exit(1 if failures else 0)
