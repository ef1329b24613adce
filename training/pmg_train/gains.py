"""Physically informed PD gains (PIG) for the Unitree G1 29-DoF: kp = I w_n^2, kd = 2 zeta I w_n per
joint, I the motor's rotor inertia reflected through its gearbox (the joint's armature).

Values: those of the public BeyondMimic G1 configuration (HybridRobotics/whole_body_tracking,
source/whole_body_tracking/whole_body_tracking/robots/g1.py; read here from its public copy in the
fork Beat-in-our-hearts/whole_body_tracking, commit cf53049ca7571f9575246671b29b082bcf0e5ed4), which
unitree_rl_lab's mimic tasks reuse:
  natural frequency w_n = 2 pi x 10 Hz = 62.83 rad/s, damping ratio zeta = 2.0;
  reflected rotor inertia per motor type [kg m^2]: 5020 0.003609725, 7520-14 (14.3:1) 0.010177520,
  7520-22 (22.5:1) 0.025101925, 4010 0.00425;
  joints: hip pitch, hip yaw, waist yaw 7520-14; hip roll, knee 7520-22; ankle pitch / roll and
  waist roll / pitch two 5020 in a parallel linkage (2 x 5020 inertia, so 2 x the gains);
  shoulder pitch / roll / yaw, elbow, wrist roll 5020; wrist pitch / yaw 4010.
Only the numbers (public constants of a physical model) are taken; nothing of its code.

  python3 training/pmg_train/gains.py --write config/robots/g1/g1_pig.yaml   # (re)writes the PIG robot config
  python3 training/pmg_train/gains.py --check config/robots/g1/g1_pig.yaml   # exit 1 if it differs (ctest
                                                                               # pig_robot_config_current)

The robot config is config/robots/g1/g1.yaml with kp / kd replaced on all 29 joint lines (rounded to
4 decimals, the values training and the exported contract use) and a comment header with the table.
No JAX here: export_onnx.py and the tests import it.
"""
from __future__ import annotations

import argparse
import math
import re
import sys

NATURAL_FREQ_HZ = 10.0
NATURAL_FREQ_RAD_S = 2.0 * math.pi * NATURAL_FREQ_HZ   # w_n [rad/s]
DAMPING_RATIO = 2.0                                    # zeta [-]
MOTOR_ARMATURE_KGM2 = {                                # reflected rotor inertia per motor [kg m^2]
    "5020": 0.003609725,
    "7520_14": 0.010177520,
    "7520_22": 0.025101925,
    "4010": 0.00425,
}
SOURCE = ("BeyondMimic G1 config (HybridRobotics/whole_body_tracking, "
          "source/whole_body_tracking/whole_body_tracking/robots/g1.py), as reused by unitree_rl_lab")
# Joint name suffix (after left_/right_) -> (motor type, motors driving the joint).
JOINT_MOTORS = {
    "hip_pitch_joint": ("7520_14", 1), "hip_roll_joint": ("7520_22", 1), "hip_yaw_joint": ("7520_14", 1),
    "knee_joint": ("7520_22", 1), "ankle_pitch_joint": ("5020", 2), "ankle_roll_joint": ("5020", 2),
    "waist_yaw_joint": ("7520_14", 1), "waist_roll_joint": ("5020", 2), "waist_pitch_joint": ("5020", 2),
    "shoulder_pitch_joint": ("5020", 1), "shoulder_roll_joint": ("5020", 1), "shoulder_yaw_joint": ("5020", 1),
    "elbow_joint": ("5020", 1), "wrist_roll_joint": ("5020", 1), "wrist_pitch_joint": ("4010", 1),
    "wrist_yaw_joint": ("4010", 1),
}
DECIMALS = 4


def motor_of(joint_name):
    """(motor type, count) of a G1 joint name; KeyError naming the joint if unknown."""
    key = re.sub(r"^(left|right)_", "", joint_name)
    if key not in JOINT_MOTORS:
        raise KeyError(f"{joint_name}: no motor type known for this joint (pmg_train/gains.py JOINT_MOTORS)")
    return JOINT_MOTORS[key]


def reflected_inertia(joint_name):
    """Reflected rotor inertia I [kg m^2] of a joint (the MuJoCo joint armature)."""
    motor, count = motor_of(joint_name)
    return count * MOTOR_ARMATURE_KGM2[motor]


def pig_gains(joint_names):
    """(kp [N m/rad], kd [N m s/rad], I [kg m^2]) lists for @p joint_names: kp = I w_n^2,
    kd = 2 zeta I w_n, kp and kd rounded to DECIMALS (what the robot config holds)."""
    inertia = [reflected_inertia(n) for n in joint_names]
    kp = [round(i * NATURAL_FREQ_RAD_S ** 2, DECIMALS) for i in inertia]
    kd = [round(2.0 * DAMPING_RATIO * i * NATURAL_FREQ_RAD_S, DECIMALS) for i in inertia]
    return kp, kd, inertia


def _fmt(x):
    return f"{x:.{DECIMALS}f}".rstrip("0").rstrip(".")


def pig_robot_yaml(nominal_text):
    """The PIG robot config text from the nominal robot config text (g1.yaml): kp / kd replaced on
    every joint line, a comment header with w_n, zeta, I per joint and the source."""
    names = re.findall(r"^\s*-\s*\{name:\s*([A-Za-z0-9_]+)\s*,", nominal_text, re.M)
    kp, kd, inertia = pig_gains(names)
    nominal_text = re.sub(r"^# PD gains:.*\n(?:#.*\n)*", "# PD gains: physically informed, see the header above.\n",
                          nominal_text, count=1, flags=re.M)
    lines = nominal_text.splitlines(keepends=True)
    out, j = [], 0
    for line in lines:
        m = re.match(r"^\s*-\s*\{name:\s*([A-Za-z0-9_]+)\s*,", line)
        if m:
            assert m.group(1) == names[j]
            line, n_kp = re.subn(r"(\bkp:\s*)[^,}]+", lambda mm: mm.group(1) + _fmt(kp[j]), line, count=1)
            line, n_kd = re.subn(r"(\bkd:\s*)[^,}]+", lambda mm: mm.group(1) + _fmt(kd[j]), line, count=1)
            if (n_kp, n_kd) != (1, 1):
                raise ValueError(f"joint line of {names[j]} has no kp / kd to replace")
            j += 1
        out.append(line)
    header = [
        "# Physically informed PD gains (PIG, issue 15): generated from g1.yaml by",
        "# `python3 training/pmg_train/gains.py --write config/robots/g1/g1_pig.yaml`; only kp / kd differ.",
        "# Do not edit by hand: ctest pig_robot_config_current checks that this file equals the generator's output.",
        f"# kp = I w_n^2, kd = 2 zeta I w_n with w_n = 2 pi x {NATURAL_FREQ_HZ:g} Hz = {NATURAL_FREQ_RAD_S:.4f} rad/s, "
        f"zeta = {DAMPING_RATIO:g},",
        "# I = the motor's reflected rotor inertia (the joint armature in training). Source of w_n, zeta and I:",
        "# " + SOURCE.replace(", source/", ",\n#   source/") + ".",
        "# Per joint: I [kg m^2], kp [N m/rad], kd [N m s/rad] (motor):",
    ]
    seen = set()
    for n, p, d, i in zip(names, kp, kd, inertia):
        key = re.sub(r"^(left|right)_", "", n)
        if key in seen:
            continue
        seen.add(key)
        motor, count = motor_of(n)
        header.append(f"#   {key:22s} I {i:.9f}  kp {_fmt(p):>8s}  kd {_fmt(d):>6s}  "
                      f"({'2 x ' if count == 2 else ''}{motor.replace('_', '-')})")
    header.append("# Deploy the policy trained with these gains with config/controller/g1_sil_table2_pig.yaml.")
    return "\n".join(header) + "\n" + "".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="gains.py", description=__doc__.split("\n")[0])
    ap.add_argument("--nominal", default="config/robots/g1/g1.yaml")
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", metavar="OUT")
    mode.add_argument("--check", metavar="FILE")
    a = ap.parse_args(argv)
    with open(a.nominal) as f:
        text = pig_robot_yaml(f.read())
    if a.write:
        with open(a.write, "w") as f:
            f.write(text)
        print("wrote", a.write)
        return 0
    with open(a.check) as f:
        same = f.read() == text
    print(f"{a.check}: {'equals' if same else 'DIFFERS from'} the PIG config generated from {a.nominal}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
