#!/usr/bin/env python3
"""How mirror-symmetric the PMG reference is (issue 12; the assumption of the mirror-symmetry loss).

The mirror-symmetry loss (pmg_train/symmetry.py) asks the actor for pi(M_o o) = M_a pi(o), with the
gait phase moved by half a cycle. That is only consistent if the reference it tracks is symmetric the
same way: q_ref(phase + 1/2, M u) = M q_ref(phase, u) for the legs. (The actor sees the reference's
joints, mirrored by the same map, so an asymmetric reference does not contradict the loss; only what
the actor infers from the phase about the reference still to come does.) This prints, per command, the RMS
and the largest difference over 20 phases (pmg_generator.step, the NumPy port of the C++ generator,
without GCO) for the clip library given, and the leg joints' RMS range of motion over the cycle for
scale.

  python3 training/reference_symmetry.py [--clips config/clips/g1_walking_height] [--scan-shift]
      [--plot PNG [--compare-clips DIR]]

--scan-shift adds, per command, the phase shift in [0.30, 0.70] (steps of 0.02) that matches the two
sides best, and its RMS difference.
--plot PNG [--compare-clips DIR] draws, for walking forward at 0.5 m/s and backward at 0.3 m/s, four
left-leg joints over the phase against the right leg's mirror image half a cycle on, for --clips and
(if given) a second clip set: where the two curves of a set lie on each other, its steps are alike.
"""
import argparse
import os
import sys

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, "training"))

COMMANDS = [  # (v_x, v_y, omega), (pitch, roll, height <= 0: standing)
    ((0.5, 0.0, 0.0), (0.0, 0.0, 0.0)), ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0)), ((-0.3, 0.0, 0.0), (0.0, 0.0, 0.0)),
    ((0.0, 0.3, 0.0), (0.0, 0.0, 0.0)), ((0.0, 0.0, 0.5), (0.0, 0.0, 0.0)), ((0.5, 0.2, 0.3), (0.0, 0.0, 0.0)),
    ((0.8, -0.2, -0.4), (0.0, 0.0, 0.0)), ((0.4, 0.0, 0.0), (0.0, 0.0, 0.68)), ((0.0, 0.0, 0.0), (0.0, 0.15, 0.0)),
]


class SideGap:
    """One command's two sides: the legs' reference q_ref(phase, u) at @p n_phases phases (pmg_generator.step,
    no GCO) and, for a phase shift, q_ref(phase + shift, M u) - M q_ref(phase, u) over the leg joints [rad].
    M u negates v_y, omega and roll (pmg_train/symmetry.COMMAND_SIGN); the legs lead the joint space (counted
    from the joint names, pmg_train/g1_env.LEG, so that this runs on NumPy alone)."""

    def __init__(self, model, js, u_d, u_s, n_phases=20):
        from pmg_train import pmg_generator as pg
        from pmg_train.symmetry import COMMAND_SIGN, mirror
        self.pg, self.model = pg, model
        self.phases = np.arange(n_phases) / float(n_phases)
        self.n_leg = sum(1 for n in js.joint_names if n.split("_")[1] in ("hip", "knee", "ankle"))
        self.q = self.q_ref(u_d, u_s, 0.0)  # (n_phases, n), all joints
        self.legs = self.q[:, :self.n_leg]
        self.mirrored = mirror(self.q, js.mirror_index, js.mirror_sign)[:, :self.n_leg]
        self.u_dm = np.array(u_d) * np.array(COMMAND_SIGN[:3])
        self.u_sm = np.array(u_s) * np.array(COMMAND_SIGN[3:])

    def q_ref(self, u_d, u_s, shift):
        """References (all joints) at the phases moved by @p shift, (n_phases, n)."""
        return np.array([self.pg.step(self.model, (p + shift) % 1.0, np.array(u_d, float), np.array(u_s, float),
                                      0.01)["q_ref"] for p in self.phases])

    def differences(self, shift):
        """q_ref(phase + shift, M u) - M q_ref(phase, u), legs, (n_phases, n_leg) [rad]."""
        return self.q_ref(self.u_dm, self.u_sm, shift)[:, :self.n_leg] - self.mirrored

    def rms(self, shift=0.5):
        return float(np.sqrt(np.mean(self.differences(shift) ** 2)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--clips", default="config/clips/g1_walking_height")
    ap.add_argument("--robot", default="config/robots/g1/g1.yaml")
    ap.add_argument("--scan-shift", action="store_true")
    ap.add_argument("--plot", default=None, metavar="PNG")
    ap.add_argument("--compare-clips", default=None, metavar="DIR", help="--plot: a second clip set beside --clips")
    args = ap.parse_args()
    from pmg_train import pmg_generator as pg
    js = pg.joint_space_from_robot_yaml(os.path.join(REPO, args.robot))
    model = pg.load_library(os.path.join(REPO, args.clips), js)
    print(f"clips {args.clips}: legs, 20 phases; q_ref(phase + 1/2, M u) - M q_ref(phase, u) [rad]")
    print(f"{'u_d (vx, vy, wz)':>22} {'u_s (pitch, roll, h)':>22} {'RMS':>7} {'max':>7} {'RMS motion':>11}"
          + (f" {'best shift':>10} {'its RMS':>7}" if args.scan_shift else ""))
    for u_d, u_s in COMMANDS:
        gap = SideGap(model, js, u_d, u_s)
        d, m = gap.differences(0.5), gap.legs
        line = (f"{str(u_d):>22} {str(u_s):>22} {np.sqrt(np.mean(d ** 2)):7.4f} {np.abs(d).max():7.4f} "
                f"{np.sqrt(np.mean((m - m.mean(0)) ** 2)):11.4f}")
        if args.scan_shift:
            rms, shift = min((float(np.sqrt(np.mean(gap.differences(s) ** 2))), s)
                             for s in np.round(np.arange(0.30, 0.701, 0.02), 2))
            line += f" {shift:10.2f} {rms:7.4f}"
        print(line, flush=True)
    if args.plot:
        plot(args, pg, js, model)


PLOT_JOINTS = ("hip_pitch", "hip_roll", "knee", "ankle_pitch")


def plot(args, pg, js, model):
    """Left leg q(phase) against M q(phase + 1/2) of the right leg, forward and backward walks (module doc)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pmg_train.symmetry import mirror
    sets = [(args.clips, model)]
    if args.compare_clips:
        sets.append((args.compare_clips, pg.load_library(os.path.join(REPO, args.compare_clips), js)))
    names = list(js.joint_names)
    phases = np.arange(60) / 60.0
    commands = (("forward 0.5 m/s", (0.5, 0.0, 0.0)), ("backward 0.3 m/s", (-0.3, 0.0, 0.0)))
    fig, axes = plt.subplots(len(commands), len(PLOT_JOINTS), figsize=(15, 6.5), sharex=True)
    for r, (label, u_d) in enumerate(commands):
        for ci, (clips, lib) in enumerate(sets):
            q = SideGap(lib, js, u_d, (0.0, 0.0, 0.0), n_phases=len(phases)).q
            mirrored = mirror(np.roll(q, -len(phases) // 2, axis=0), js.mirror_index, js.mirror_sign)  # M q(phase + 1/2)
            colour = f"C{ci}"
            for c, j in enumerate(PLOT_JOINTS):
                k = names.index(f"left_{j}_joint")
                ax = axes[r, c]
                rms = float(np.sqrt(np.mean((q[:, k] - mirrored[:, k]) ** 2)))
                ax.plot(phases, q[:, k], color=colour, label=f"{os.path.basename(clips)}: left (RMS gap {rms:.3f})")
                ax.plot(phases, mirrored[:, k], color=colour, ls="--", label="  right, mirrored, half a cycle on")
                ax.set_title(f"{label}: left_{j}", fontsize=9)
                if r == len(commands) - 1:
                    ax.set_xlabel("phase")
                if c == 0:
                    ax.set_ylabel("rad")
                ax.legend(fontsize=6, loc="best")
    fig.suptitle("PMG reference (no GCO): each step against the other foot's step, mirrored", fontsize=11)
    fig.tight_layout()
    fig.savefig(args.plot, dpi=110)
    print("wrote", args.plot)


if __name__ == "__main__":
    main()
