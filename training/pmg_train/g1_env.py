"""G1 29-DoF PMG-tracking environment in MuJoCo MJX (Brax `Env` interface), for PPO.

Same robot as the SIL: config/robots/g1/g1_29dof_rev_1_0.xml (foot spheres + floor collide), the
joint defaults the SIL's MuJoCo 2.2 model gets (armature 0.01 kg m^2, damping 0.05 N m s/rad,
frictionloss 0.2 N m), motor PD with the robot config's kp/kd, the controller's 10 ms period.

Limb separation (PMG paper): the actor commands the 12 leg joints (q_des = default + scale * a);
the waist and arms follow the PMG reference open-loop (plus smooth random perturbations of the
arm targets during training). PMG references come from training/pmg_train/pmg_generator.py, the
port proven equal to the C++ generator (test/policy: pmg_port_*).

Teleoperation of the arms (issue 13; EnvConfig.p_teleop > 0): in teleop segments the arm targets
are what VR teleoperation sends instead (pmg::teleop::TeleopMode: arm IK, absolute joint targets):
each arm's target moves in a straight line in joint space (largest joint speed 0.3-2 rad/s)
between random waypoints held 0.5-3 s, drawn within the joint limits over the teleop envelope
(TELEOP_LO/HI: shoulder pitch -1.8..0.5 rad, outward shoulder roll, shoulder yaw +-1, elbow
-0.9..1.9, wrists +-1); half of the waypoints move both arms forward together, mirrored
("carrying", TELEOP_CARRY_*). An arm passes between the PMG reference and its teleop target with a
blend weight that moves at 1/s (engage / return, as the controller's teleop stage and rate limiter
make them continuous). Segments are drawn every `command_resample` steps (with the command): with
probability p_teleop teleop is on, then each arm follows with probability p_teleop_arm. Hand
payloads (0-1.5 kg, in a share p_payload of the environments per hand) are added to the masses of
the wrist_yaw_link bodies (which carry the rubber hands) by the domain randomisation. Brax's
auto-reset keeps `info`, so draws made in reset() hold per environment slot; the teleop state is
set back to the default arm pose when an episode ends (the robot restarts in it).

PD gains (EnvConfig.gains, issue 15): "nominal" = the robot config's kp / kd with armature
0.01 kg m^2 (the Baseline policy); "physically_informed" = kp = I w_n^2, kd = 2 zeta I w_n per joint
with I the motor's reflected rotor inertia, w_n = 2 pi 10 Hz, zeta = 2 (pmg_train/gains.py: the
BeyondMimic G1 values, source cited there), and the joints' armature is I too (the generic armature
DR becomes I x U(0.8, 1.5)). config/robots/g1/g1_pig.yaml holds the same kp / kd for the controller.

Actuator models (EnvConfig.actuators, issue 15): a calibrated robot config as pmg_calib_joints
writes it (the robot config with `actuator:` blocks, inline or as file paths, on the calibrated
joints; keys of include/pmg/calib/actuator_yaml.hpp). For every joint with a block, each physics
substep (5 ms) applies the identified model of pmg::calib::ActuatorModel (its port,
pmg_train/actuator.py, equal to the C++ model: ctest actuator_port_equals_cpp):
  - gain scales: kp x kp_scale, kd x kd_scale (of the gains above); armature_kgm2 -> dof_armature;
  - transport delay: the command goes through the port's delay line (linear interpolation between
    substeps, so delays that are fractions of 5 ms act as fractions);
  - torque constant, saturation, torque-speed envelope: tau = limit(kt_scale (kp (q_des' - q) +
    kd (qd_des' - dq))) with the joint's torque limit as the upper bound of torque_limit_Nm;
  - the D term stays implicit for stability at 5 ms (as for the nominal joints): dof_damping =
    0.05 + kt_scale kd + fv (viscous friction too), and the explicit kt_scale kd dq goes into
    qfrc_applied, so the total is the model's explicit torque (saturated when it saturates) plus the
    stabilising implicit -c (dq_next - dq);
  - dry friction: MJX's dof_frictionloss (a constraint, so MuJoCo's solver provides the stiction),
    set every substep to the port's kinetic friction at the current velocity and motor torque,
    fc + (max(fs, fc) - fc) exp(-(dq/vs)^2) + kl |tau| (the break-away torque at rest). The port's
    own implicit stiction needs this step's mass-matrix diagonal and bias forces before the step,
    which mjx.step does not expose (a second forward pass per substep would double the cost).
    MJX keeps a friction row only for dofs whose frictionloss was > 0 when the model was put
    (all joints: 0.2 N m), and a row with frictionloss 0 locks the joint: floor 1e-5 N m.
  - not applied: offset_rad and the file's zero_offsets (the deployed controller corrects zero
    offsets: the "Dynamic + Zero-point" policy differs only in its robot config), rate_hz (drivers at
    >= 200 Hz run at least once per 5 ms substep; a lower rate is reported), backlash (refused).
Domain randomisation around the identified values: per episode each identified parameter is
value x U(1 - dr, 1 + dr), independently per joint (the identified value itself with
deterministic_reset): kp_scale and kd_scale always (a block omits them at 1), and every other key the
block names (armature, delay, kt_scale, torque limit, envelope, fc, fs, kl, fv); unnamed effects stay
off. The width is sized from the calibration: where the joint's `actuator_uncertainty:` gives the
parameter's uncertainty u (pmg_calib_joints: the spread of its cross-validation fits, at least the
search's resolution), dr = z u / |value| (EnvConfig.actuator_dr_z, 2), clipped to
[actuator_dr_min, actuator_dr_max] = [0.02, 0.5] (a floor so that the policy never trains on one
exact value; a ceiling so that a poorly determined parameter does not swamp the model); a randomised
key without an uncertainty (a gain scale the calibration did not fit) gets EnvConfig.actuator_dr.
They replace the generic kp / kd / armature / frictionloss ranges on those joints; joints without a
block keep the generic ranges.

Configurations (EnvConfig.mode; the seed's Table I ablation, trained alike):
  "pmg_gco"     full PMG: generator + GCO (pmg_train/gco.py, equal to the C++ GeneratorWithGco,
                ctest gco_port_equals_cpp); the actor observes u' (PMG eq. 19) as its command.
  "pmg"         PMG without GCO: the actor observes the command u.
  "single_gait" single-gait imitation: the reference is the generator run on the walk_forward clip
                alone at its nominal speed, whatever the command (no blending, no posture clips,
                blending "paper"); the actor observes u.
In every mode the task rewards track the USER's command u (issue 12): base velocity (v_x, v_y) and
yaw rate against u's, torso pitch / roll against the commanded pitch / roll, pelvis height against
the commanded height; u' only shapes the reference (and is what the pmg_gco actor observes, as the
C++ runtime feeds it).

Generator (EnvConfig.blending, default "consistent" as the controller's GeneratorParams): the clip
folder EnvConfig.clips (config/clips/g1) is read from the files at construction, including each
clip's implied_motion table and consistency_map.yaml (pmg_generator.load_library).

Command distribution (every command_resample steps, _sample_command; over the issue-12 envelope
v_x [-0.5, 1.0] m/s, v_y [-0.4, 0.4] m/s, w [-0.8, 0.8] rad/s, pitch [-0.1, 0.4] rad, roll
[-0.2, 0.2] rad, height [0.62, 0.78] m): p_single_axis (40 %) one velocity axis alone, p_combined
(40 %) a combined velocity (all three axes, or two with probability p_two_axes), the rest (20 %)
standing (zero velocity). A posture is commanded with probability p_posture_walk (40 %) while
walking (walking crouched / bent / leaning) and p_posture_stand (75 %) while standing; a commanded
posture sets each of pitch, roll, height with probability p_posture_axis (else neutral), at least
one. Values are uniform in their ranges. A focus box (EnvConfig.p_focus, command_focus; off by
default) replaces a draw with one uniform in a sub-box of the envelope (focus_box).

Observation (actor, 62 values, order = policy contract terms):
  base_ang_vel_B (3)  projected_gravity_B (3)  command (6: vx, vy, wz, pitch, roll, height)
  joint_pos_rel (12)  joint_vel (12)  last_action (12)  pmg_ref_q_rel (12)  pmg_phase (2: sin, cos)
Raw values are SI; the contract's per-term scales are applied here exactly as the C++
ObservationAssembler does (scale, then clip to +-obs_clip).
External hand forces (EnvConfig.p_hand_force > 0, issue 14; `--hand-forces`): in teleop segments a
teleoperated hand gets, with probability p_hand_force per hand and segment, a constant world-frame
force at its wrist_yaw_link body (xfrc_applied): vertical U(hand_force_z) N (positive up: the table
pushing back on a pressing hand), horizontal of uniform direction and magnitude U(0, hand_force_xy) N
(friction of a hand dragged over a surface, an object pushed or held). The applied force follows the
target times the arm's teleop blend weight at hand_force_rate N/s per component, so it is continuous,
and is zero again when the episode ends. The actor does not observe it (it must read it from its own
state, as on the robot); the critic neither (its input stays as before, so runs restore earlier
checkpoints).

Upper-body feed-forward (EnvConfig.upper_body_ff, issue 14; `--upper-body-ff`): the controller's
`upper_body:` stage in the environment. Once per control step the three waist joints get the gravity
torque of everything beyond them (nominal masses, the last physics step's pose: waist_gravity, equal
to MuJoCo's qfrc_bias at zero velocity) minus upper_body_damping x qd, clamped, on top of their PD
torque. An actor trained with it is deployed with `upper_body: enabled: true` (its contract's
pmg.upper_body_ff).

Reference state initialisation (EnvConfig.p_reset_reference, `--p-reset-reference`; off by default):
with that probability a reset puts the robot in the PMG reference's pose for its first command and
phase (all 29 joints, plus the reset's joint noise) instead of the standing pose, the pelvis upright and
lowered or raised until the lowest sole sphere touches the floor, at rest. A crouched or bent command
then starts crouched or bent, and a walking one mid-stride, so the policy meets those states and their
rewards before it has learned to reach them (DeepMimic's reference state initialisation). In PPO
training, Brax's AutoResetWrapper (0.14.2) restarts a finished episode from the physics state of the
environment's first reset and keeps the rest of its state (command, phase, GCO state) running: so a
share p_reset_reference of the environments restart every episode in the reference pose of their first
command and phase, whatever the command is then, and the rest standing.

Privileged critic observation: the actor's terms without noise, plus base linear velocity in the
heading frame, pelvis height, measured and PMG foot contacts, torso pitch/roll, kp scale, delay,
the 14 arm joint targets (relative to the default pose) and the two hand payloads [kg] (90 values).
The actor's observation does not change (the arms are not in it: the contract stays the same).
"""
from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from brax.envs.base import Env, State
from mujoco import mjx

from . import actuator as act_port
from . import gains as gains_mod
from . import gco as gco_port
from . import pmg_generator as pg

LEG = 12
OBS_TERMS = [  # (name, size, scale) -- the policy contract's observation layout
    ("base_ang_vel_B", 3, 0.25),
    ("projected_gravity_B", 3, 1.0),
    ("command", 6, [2.0, 2.0, 0.25, 1.0, 1.0, 1.0]),
    ("joint_pos_rel", LEG, 1.0),
    ("joint_vel", LEG, 0.05),
    ("last_action", LEG, 1.0),
    ("pmg_ref_q_rel", LEG, 1.0),
    ("pmg_phase", 2, 1.0),
]
OBS_CLIP = 100.0
ARM0 = 15      # first arm joint (robot order): left shoulder pitch .. left wrist yaw, then the right arm
ARM = 14
# Teleop envelope of the LEFT arm (shoulder pitch, roll, yaw, elbow, wrist roll, pitch, yaw) [rad];
# the right arm's is its mirror image (MIRROR_SIGN, the robot config's mirror_sign). Shoulder pitch
# negative = arm forward/up; left shoulder roll positive = outward.
TELEOP_LO = (-1.8, -0.1, -1.0, -0.9, -1.0, -1.0, -1.0)
TELEOP_HI = (0.5, 1.6, 1.0, 1.9, 1.0, 1.0, 1.0)
# Both arms forward together ("carrying"): left arm in this sub-envelope, right arm its mirror.
TELEOP_CARRY_LO = (-1.6, -0.1, -0.5, -0.6, -1.0, -1.0, -1.0)
TELEOP_CARRY_HI = (-0.2, 0.5, 0.5, 1.6, 1.0, 1.0, 1.0)
MIRROR_SIGN = (1.0, -1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
GAINS = ("nominal", "physically_informed")
NOMINAL_ARMATURE = 0.01     # kg m^2, the SIL's MuJoCo 2.2 joint armature (nominal gains)
MODEL_FRICTIONLOSS = 0.2    # N m: the SIL model's joint friction (module docstring)
FRICTIONLOSS_FLOOR = 1e-5   # N m: MJX keeps a dof's friction row only if its frictionloss was > 0 when the
                            # model was put, and a row with frictionloss 0 turns into a hard velocity lock
# Identified actuator parameters drawn per episode around the identified value (EnvConfig.actuator_dr);
# the other keys of the block are used as identified (vs_rad_per_s) or not at all (offset_rad, rate_hz,
# backlash_gap_rad: module docstring "Actuator models").
ACT_DR_KEYS = ("kp_scale", "kd_scale", "armature_kgm2", "delay_s", "kt_scale", "torque_limit_Nm", "tau_stall_Nm",
               "w_max_rad_per_s", "fc_Nm", "fs_Nm", "kl", "fv_Nms_per_rad")
ACT_KEYS = ACT_DR_KEYS + ("vs_rad_per_s",)


def load_actuator_blocks(path, joint_names):
    """The `actuator:` blocks of a calibrated robot config (pmg_calib_joints --out; the robot config
    format, docs/calibration.md): {joint name: parsed block (actuator.parse_block)}. A block is an
    inline map or the path of an actuator file (a top-level `actuator:` map, relative to @p path).
    Each parsed block also holds "_named": the keys the block gives. Joints must be among
    @p joint_names. The file's top-level `zero_offsets:` is not read (training never applies encoder
    offsets: the deployed controller corrects them). Raises ValueError naming the file, joint and key."""
    import os

    import yaml
    with open(path) as f:
        doc = yaml.safe_load(f)
    if not isinstance(doc, dict) or not isinstance(doc.get("joints"), list):
        raise ValueError(f"{path}: expected a robot config with a `joints:` list")
    known = set(joint_names)
    blocks = {}
    for i, j in enumerate(doc["joints"]):
        name = j.get("name") if isinstance(j, dict) else None
        if name not in known:
            raise ValueError(f"{path}: joints[{i}].name = {name!r}: not a joint of the training robot")
        block = j.get("actuator")
        if block is None:
            continue
        where = f"{path}: joints.{name}.actuator"
        if isinstance(block, str):
            afile = os.path.join(os.path.dirname(os.path.abspath(path)), block)
            with open(afile) as f:
                adoc = yaml.safe_load(f)
            if not isinstance(adoc, dict) or set(adoc) != {"actuator"}:
                raise ValueError(f"{where}: file {afile!r} must hold exactly one top-level `actuator:` map")
            block, where = adoc["actuator"], f"{afile}: actuator"
        parsed = act_port.parse_block(block, where)
        if parsed["backlash_gap_rad"] > 0:
            raise ValueError(f"{where}.backlash_gap_rad = {parsed['backlash_gap_rad']}: backlash needs a rotor "
                             f"body; the training model (like the G1 SIL) does not model it (expected 0)")
        parsed["_named"] = tuple(block)
        unc = j.get("actuator_uncertainty") or {}
        uwhere = f"{path}: joints.{name}.actuator_uncertainty"
        if not isinstance(unc, dict):
            raise ValueError(f"{uwhere}: expected a map {{actuator key: uncertainty}}")
        for k, v in unc.items():
            if k not in block:
                raise ValueError(f"{uwhere}.{k}: not a parameter the joint's `actuator:` block names "
                                 f"(expected one of {sorted(block)})")
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError(f"{uwhere}.{k} = {v!r}: expected a finite value >= 0 (the parameter's unit)")
        parsed["_uncertainty"] = {k: float(v) for k, v in unc.items()}
        blocks[name] = parsed
    for i, j in enumerate(doc["joints"]):
        if isinstance(j, dict) and j.get("actuator_uncertainty") is not None and j.get("actuator") is None:
            raise ValueError(f"{path}: joints.{j.get('name')}.actuator_uncertainty: the joint has no `actuator:` block")
    return blocks


@dataclasses.dataclass
class EnvConfig:
    mode: str = "pmg_gco"          # "pmg_gco" | "pmg" | "single_gait" (see the module docstring)
    blending: str = "consistent"   # generator blending: "consistent" | "paper" (ablation); single_gait: paper
    # Beyond the paper, both off for every policy trained before 2026-11-27 (docs/policy.md
    # "Reference torso pitch"): the walking clips' mean waist lean removed (GeneratorParams::
    # upright_walking), and the reference's stance soles levelled before GCO (GcoOptions::
    # sole_levelling, gco.level_soles; pmg_gco mode only). The controller config must match
    # (generator.upright_walking, sole_levelling); the ONNX contract records both.
    upright_walking: bool = False
    sole_levelling: bool = False
    # The stride adaptation (GcoOptions::stride_adaptation, gco.adapt_strides; pmg_gco mode only, since
    # 2026-12-04): the reference's stance soles held still under the command, after the levelling and
    # before GCO. The controller config's `stride_adaptation` must match; the ONNX contract records it.
    stride_adaptation: bool = False
    clips: str = "config/clips/g1"  # clip folder (clips + implied_motion tables + consistency_map.yaml)
    gco_model: str = "training/pmg_train/gco_g1.json"
    mjcf: str = "config/robots/g1/g1_29dof_rev_1_0.xml"
    robot_yaml: str = "config/robots/g1/g1.yaml"
    control_dt: float = 0.01       # s, controller period (contract control_period)
    sim_dt: float = 0.005          # s, physics step (PD recomputed every physics step)
    episode_length: int = 1000     # control steps (10 s)
    command_resample: int = 400    # control steps between command changes
    # Command shaping as the controller's `commands:` block does it (include/pmg/controller/commands.hpp,
    # config/controller/g1_sil_policy_wh6g.yaml): with command_slew the drawn command is a goal the command
    # (what the generator, the observation and the task rewards get) moves towards at most
    # command_max_accel [m/s^2, m/s^2, rad/s^2] on v_x, v_y, w, command_posture_rate [rad/s] on pitch
    # and roll and command_height_rate [m/s] on the height, per control step. Off (the default, as
    # every policy so far was trained): the command jumps to the drawn one, which the SIL never does.
    command_slew: bool = False
    command_max_accel: tuple = (1.0, 1.0, 2.0)
    command_posture_rate: float = 0.5
    command_height_rate: float = 0.2
    # The controller's velocity envelopes and walking height floor on the shaped command (with
    # command_slew; shape_with_envelopes, a port of CommandShaper::update in src/controller/commands.cpp,
    # proven equal to it by training/tests/test_command_envelopes.py): the crouched envelope (at and
    # below crouched_height [m] sum_i |u_i| / m_i <= 1, blended from the standing height), the bent
    # envelope (at bent_pitch [rad] |u_i| <= b_i, blended from upright), and the walking height floor
    # (walking and for walking_min_height_hold_s [s] after, the height goal is at least
    # walking_min_height [m]), each on the shaped posture, with the squat clip's neutral as the standing
    # height, as the controller sets it. Goals beyond envelope_max_velocity (the training ranges reach
    # past the controller's box for the velocity feedback's headroom) keep that headroom upright, and a
    # crouch or a bend brings them inside (envelope_scales). Off (the default, as every policy so far was
    # trained): the actor is trained on crouched and bent commands the product path never gives it
    # (walking at 0.59 m, 1.2 m/s crouched; training/command_gap.py counts them). The values are
    # config/controller/g1_sil_policy_wh6g.yaml's `commands:` (train_pmg.py --command-envelopes reads them; the
    # default config's per-axis crouched box is trained as the crouched envelope off, crouched_height 0).
    command_envelopes: bool = False
    envelope_max_velocity: tuple = (1.0, 0.4, 0.8)
    crouched_height: float = 0.62
    crouched_max_velocity: tuple = (0.3, 0.3, 0.6)
    bent_pitch: float = 0.4
    bent_max_velocity: tuple = (0.8, 0.4, 0.8)
    walking_min_height: float = 0.66
    walking_min_height_hold_s: float = 1.5
    # Command ranges (heading frame), uniform: the issue-12 envelope.
    vx: tuple = (-0.5, 1.0)
    vy: tuple = (-0.4, 0.4)
    wz: tuple = (-0.8, 0.8)
    pitch: tuple = (-0.1, 0.4)
    roll: tuple = (-0.2, 0.2)
    height: tuple = (0.62, 0.78)
    # Command mix (module docstring): velocity kind, then the posture.
    p_single_axis: float = 0.4     # one velocity axis alone
    p_combined: float = 0.4        # combined velocity (the rest: standing, zero velocity)
    p_two_axes: float = 0.5        # share of the combined commands with exactly two axes
    # Stops: at a resample after a walking goal, the new goal's velocity is zero with this
    # probability (its posture drawn as usual). 0 (the default, as every policy so far): about 20 %
    # of the draws stand, so a stop from a fast walk (>= 0.8 m/s) is rare (about 1 % of the segment changes).
    p_stop: float = 0.0
    # A stop keeps the walking goal's posture with this probability (else its posture is drawn as
    # usual). 0 (the default, as every policy so far): a stop at the same crouch, the user letting go
    # of the stick while crouched, is rare, about 1 in 3 stops from a crouched walk.
    p_stop_keep_posture: float = 0.0
    p_posture_walk: float = 0.4    # posture commanded while walking (crouched / bent / leaning)
    # A focus box: with probability p_focus a drawn goal is instead uniform in command_focus, a dict
    # {axis: (lo, hi)} over COMMAND_AXES (vx, vy [m/s], wz [rad/s], pitch, roll [rad], height [m]), each
    # inside that axis's range above; an axis not named is zero (velocity) or neutral (pitch 0, roll 0,
    # the standing height). It weights a corner of the envelope the plain mix seldom draws, e.g. walking
    # backward crouched (vx -0.6..-0.3 at 0.66-0.72 m: about 1 % of the plain draws). Stops (p_stop) act
    # on it as on any goal. 0 (the default, as every policy so far): the plain mix, the same random stream.
    p_focus: float = 0.0
    command_focus: dict = dataclasses.field(default_factory=dict)
    p_posture_stand: float = 0.75  # posture commanded while standing
    p_posture_axis: float = 0.6    # each posture axis set in a commanded posture (at least one)
    # Reference state initialisation: with this probability an episode starts in the PMG reference's
    # pose for its first command and phase (all 29 joints, the lowest sole sphere on the floor, at
    # rest) instead of the standing pose, so that a policy meets crouched, bent and mid-stride states
    # from its first steps rather than only after it has learned to reach them (module docstring: how
    # Brax's auto-reset repeats it). 0 (the default, as every policy so far): every episode starts standing.
    p_reset_reference: float = 0.0
    # Domain randomisation.
    friction: tuple = (0.4, 1.25)
    mass_scale: tuple = (0.9, 1.1)
    payload: tuple = (-1.0, 2.0)   # kg added to the torso
    armature: tuple = (0.008, 0.015)
    frictionloss: tuple = (0.1, 0.3)
    kp_scale: tuple = (0.9, 1.1)
    kd_scale: tuple = (0.8, 1.2)
    p_delay: float = 0.5           # probability of one control period of action latency
    # Identified actuator models (issue 15; module docstring "Actuator models"): a calibrated robot
    # config (pmg_calib_joints --out: the robot config with `actuator:` blocks on some joints); "" = none.
    actuators: str = ""
    # Per-episode DR around each identified value (module docstring "Actuator models"): a parameter the
    # calibration gives an uncertainty u for (`actuator_uncertainty:`) is drawn within +- z u, as a
    # relative half-width clipped to [actuator_dr_min, actuator_dr_max]; any other randomised key within
    # +- actuator_dr (relative).
    actuator_dr: float = 0.1
    actuator_dr_z: float = 2.0
    actuator_dr_min: float = 0.02
    actuator_dr_max: float = 0.5
    # PD gains: "nominal" (robot config kp/kd, armature 0.01) or "physically_informed" (kp = I w_n^2,
    # kd = 2 zeta I w_n, armature I: pmg_train/gains.py, config/robots/g1/g1_pig.yaml).
    gains: str = "nominal"
    # Action scale (rad per unit action, per leg joint): "motion" = 1.2 x the clips' largest deviation
    # from the standing pose, clipped to [0.25, 1.2] rad; "torque_matched" = that x kp_nominal / kp, so
    # that an action commands the same PD torque offset whatever the gains (with physically informed
    # gains, 1.5-3.7x softer, the motion scale leaves the hip pitch 19 of the nominal 70 N m; issue 15).
    # With nominal gains both rules are the same. "posture" = the larger of "motion" and 1.2 x each static
    # clip's largest offset from its neutral row over this config's pitch, roll and height ranges, clipped to
    # [0.25, 2.0] rad: "motion" looks at the walking clips only, and with it the squat's rows below about
    # 0.66 m lie outside every target the actor can command (training/results/fidelity/action_range/README.md).
    # The ONNX contract carries the scale.
    action_scale_rule: str = "motion"
    # What an action is added to (leg joints): "default" = the standing pose (q_des = q_stand + scale a,
    # the paper's and every shipped actor's); "reference" = the PMG reference of this control step
    # (q_des = q_ref + scale a: a residual on the generated motion, so that the untrained actor, a = 0,
    # already steps with the reference; beyond the paper, tried for the training-time target of issue
    # 12 and not adopted: training/README.md). Such an actor is not exported to ONNX: the controller
    # deploys standing-pose offsets only.
    action_offset: str = "default"
    # Leg position targets clamped to the joint limits, as the deployed HAL supervisor clamps every
    # setpoint (src/hal/safety/envelope.cpp, clampSetpoint); matters where kp x scale reaches past a limit.
    clamp_targets: bool = True
    # The PD's D term: "implicit" (every actor so far) puts kd into dof_damping, so the Euler step
    # integrates -kd qd implicitly (stable at 5 ms); "explicit" computes tau = kp (q_des - q) + kd (qd_des - qd)
    # from each substep's measured qd, as the SIL's motor-driver emulator and the real drivers do (saturation
    # included), leaving dof_damping at the joints' own 0.05 N m s/rad (and the DR's kd scale unused).
    # Identified actuator models keep their own split (implicit) and refuse "explicit".
    pd_damping: str = "implicit"
    # Joint stops (the limit constraints' solref time constant [s] on every hinge joint): 0 keeps the
    # MJCF's (MuJoCo's default 0.02 s), soft enough that crouched walks press the ankles 0.06 rad past
    # their range. The SIL models metal stops (0.004 s, mujoco.joint_stops); here at least 2 physics steps.
    joint_stop_timeconst: float = 0.0
    # Pushes (robustness; issue 12: falls): every push_interval [s] (uniform) the base gets a
    # horizontal velocity change of uniform direction and magnitude in push_vel [m/s] (world frame),
    # as a shove of a few hundred N for a few control periods would; none with deterministic_reset.
    push_interval: tuple = (4.0, 8.0)
    push_vel: tuple = (0.0, 0.4)
    # Leg-against-leg contacts (shin and foot capsules, LEG_COLLISION_PAIRS): the SIL and the robot
    # have them; without them the policy learns gaits whose legs hook into each other.
    leg_collisions: bool = True
    arm_perturb: float = 0.3       # rad, max amplitude of smooth arm-target perturbations
    # Teleoperated arms (module docstring): share of the command segments with teleop on, the
    # share of the arms that follow then, waypoint hold time [s], largest joint speed [rad/s],
    # share of mirrored two-arm ("carrying") waypoints, blend speed between PMG and teleop [1/s].
    p_teleop: float = 0.6
    p_teleop_arm: float = 0.9
    teleop_hold: tuple = (0.5, 3.0)
    teleop_speed: tuple = (0.3, 2.0)
    p_teleop_carry: float = 0.5
    teleop_blend_rate: float = 1.0
    hand_payload: tuple = (0.0, 1.5)   # kg added to each hand (wrist_yaw_link)
    p_payload: float = 0.5             # share of environments with a payload, per hand
    # External hand forces (issue 14: wiping presses a hand on a table and drags it along, pushing or
    # holding an object loads the hands; module docstring "External hand forces"): in a teleop segment
    # each teleoperated hand gets, with probability p_hand_force, a constant world-frame force at its
    # body (wrist_yaw_link): vertical in hand_force_z [N] (up = a surface pushing back), horizontal of
    # uniform direction and magnitude up to hand_force_xy [N]; scaled by the arm's teleop blend weight
    # and slewed at hand_force_rate [N/s] per component (contact forces build up, never jump).
    p_hand_force: float = 0.0
    hand_force_z: tuple = (-20.0, 40.0)
    hand_force_xy: float = 25.0
    hand_force_rate: float = 100.0
    # Upper-body gravity compensation (issue 14; the controller's `upper_body:` section,
    # src/controller/upper_body.cpp, docs/controller.md "Upper-body gravity compensation"): once per
    # control step each waist joint gets tau_ff = g(q) - upper_body_damping * qd, clamped to
    # +-min(upper_body_max_torque, torque limit), added to its PD torque and held over the substeps, as
    # the controller writes the motor command's tau_ff once per 10 ms tick. g is the gravity torque of
    # everything beyond the joint, from the NOMINAL masses (what the controller's model knows: the torso
    # and hand payloads of the DR are not in it) at the measured pose (the last physics step's
    # kinematics, 5 ms old). Off (every shipped actor so far): the waist follows PMG on its PD alone.
    upper_body_ff: bool = False
    upper_body_damping: float = 5.0
    upper_body_max_torque: float = 40.0
    noise: dict = dataclasses.field(default_factory=lambda: {"gyro": 0.1, "gravity": 0.03, "q": 0.01, "qd": 0.5})
    deterministic_reset: bool = False  # evaluation: default pose, phase 0, nominal motors, no latency
    # Width of the velocity-tracking rewards exp(-err^2 / sigma) [(m/s)^2, (rad/s)^2]. With 0.25 a
    # 0.12 m/s shortfall (40 % of a -0.3 m/s backward command) costs 6 % of the term; 0.05: 25 %.
    lin_vel_sigma: float = 0.25
    yaw_rate_sigma: float = 0.25
    # Width of the torso-attitude reward exp(-((pitch - u_pitch)^2 + (roll - u_roll)^2) / sigma) [rad^2].
    # With 0.05 a 0.06 rad lean nobody commanded (cross-coupling; issue 12's bound is 0.05) costs 7 %
    # of the term; 0.01: 30 %.
    orientation_sigma: float = 0.05
    # Width of the pelvis-height reward exp(-(h - u_h)^2 / sigma) [m^2]. With 0.005 a robot walking
    # 15 mm below its commanded height (Table I's Height column) loses 4 % of the term; 0.001: 20 %.
    height_sigma: float = 0.005
    # Reward weights (per control step). foot_slip multiplies the summed horizontal speed [m/s] of the
    # feet touching the floor (a penalty when negative; 0, the default, leaves it out of the reward): the
    # actors trained from scratch slide their stance feet (0.12-0.30 m/s in the SIL against the default's
    # 0.07; training/README.md "A foot-slip penalty"). lin_vel_abs and yaw_rate_abs multiply the tracking
    # errors themselves, |u_xy - v_xy| [m/s] and |u_w - w_z| [rad/s] (penalties when negative; 0 leaves them
    # out): the Gaussian terms above are flat beyond about two widths (with sigma 0.05, past 0.3 m/s of error
    # exp(-err^2/sigma) < 0.2 % of its weight), so an actor that overshoots a command by more has no gradient
    # back towards it from them (training/README.md "The runaway is a run"). flight multiplies 1 on
    # a control step that ends with neither foot touching the floor (a penalty when negative; 0 leaves it
    # out): PMG's gaits are walks and never leave the floor, while the actors trained from scratch run their
    # crouched backward walks away with both feet off the floor for 32-51 % of the time (the default: 5-13 %;
    # eval_mjx.py's gait columns, same README section).
    w: dict = dataclasses.field(default_factory=lambda: {
        "lin_vel": 1.5, "yaw_rate": 0.8, "orientation": 0.5, "height": 0.5, "ref_q": 1.0, "ref_qd": 0.2,
        "contact": 0.5, "energy": -2e-4, "action_rate": -0.01, "alive": 0.5, "termination": -10.0,
        "foot_slip": 0.0, "lin_vel_abs": 0.0, "yaw_rate_abs": 0.0, "flight": 0.0})


# The reward's terms, in the order they are summed (G1PmgEnv.step): each control step's weighted value of
# term NAME is the metric "reward_NAME" (0 for the optional terms whose weight is 0), and their sum is the
# step's reward (before a non-finite reward is replaced by 0). eval_mjx.py reports them per segment, so a
# gait's reward can be read term by term (training/README.md "Which terms the runaway loses").
# The last four are optional: they enter the reward (and the compiled step) only with a weight != 0.
OPTIONAL_REWARD_TERMS = ("foot_slip", "lin_vel_abs", "yaw_rate_abs", "flight")
REWARD_TERMS = ("lin_vel", "yaw_rate", "orientation", "height", "ref_q", "ref_qd", "contact", "energy",
                "action_rate", "alive", "termination") + OPTIONAL_REWARD_TERMS


def _quat_to_rot(q):
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _pitch_roll(R):
    """Pitch (about y, positive = forward bend) and roll (about x) of rotation R_WB (ZYX Euler)."""
    pitch = jnp.arcsin(jnp.clip(-R[2, 0], -1.0, 1.0))
    roll = jnp.arctan2(R[2, 1], R[2, 2])
    return pitch, roll


LEG_COLLISION_PAIRS = (("left_thigh_collision", "right_thigh_collision"),
                       ("left_shin_collision", "right_shin_collision"),
                       ("left_foot_collision", "right_shin_collision"),
                       ("right_foot_collision", "left_shin_collision"),
                       ("left_foot_collision", "right_foot_collision"))
"""Leg-against-leg contacts the training model keeps (explicit MJCF <pair>s, condim 3): side-steps
and turns bring one shin or foot against the other leg; the SIL (full collision meshes) and the real
robot have those contacts, and a policy trained without them hooks one leg behind the other and
falls (docs/policy.md, "Why it fell")."""


def mjx_friendly_mjcf(path, leg_collisions=True):
    """The SIL's MJCF text for MJX: visual-only mesh geoms (contype 0, density 0, so no effect on
    dynamics) and their mesh assets removed; the four shoulder cylinders made non-colliding (MJX
    lacks some of their collision pairs). Collisions left: 8 foot spheres against the floor and,
    with @p leg_collisions, the leg-against-leg pairs LEG_COLLISION_PAIRS between capsules that
    MuJoCo fits to the thigh (hip_yaw_link), shin (knee_link) collision meshes and the foot
    (ankle_roll_link mesh) of each side
    (compiler fitaabb: the capsule encloses the mesh's bounding box, so it errs on the side of
    contact). Mesh files are resolved against @p path's meshdir."""
    import os
    import re
    with open(path) as f:
        xml = f.read()
    if leg_collisions:
        for side in ("left", "right"):
            xml, n_shin = re.subn(rf'<geom type="mesh" rgba="[^"]*" mesh="{side}_knee_link"/>',
                                  f'<geom name="{side}_shin_collision" type="capsule" mesh="{side}_knee_link" '
                                  'contype="0" conaffinity="0" group="3"/>', xml)
            xml, n_thigh = re.subn(rf'<geom type="mesh" rgba="[^"]*" mesh="{side}_hip_yaw_link"/>',
                                   f'<geom name="{side}_thigh_collision" type="capsule" mesh="{side}_hip_yaw_link" '
                                   'contype="0" conaffinity="0" group="3"/>', xml)
            xml, n_foot = re.subn(rf'(<geom [^>]*mesh="{side}_ankle_roll_link"/>)',
                                  rf'\1<geom name="{side}_foot_collision" type="capsule" '
                                  f'mesh="{side}_ankle_roll_link" contype="0" conaffinity="0" density="0" group="3"/>',
                                  xml)
            if (n_thigh, n_shin, n_foot) != (1, 1, 1):
                raise ValueError(f"{path}: expected one collision mesh geom each of {side}_hip_yaw_link and "
                                 f"{side}_knee_link and one {side}_ankle_roll_link mesh geom, found "
                                 f"{n_thigh}, {n_shin}, {n_foot}")
        pairs = "".join(f'<pair geom1="{a}" geom2="{b}" condim="3"/>' for a, b in LEG_COLLISION_PAIRS)
        xml = xml.replace("</mujoco>", f"<contact>{pairs}</contact></mujoco>")
        meshdir = re.search(r'meshdir="([^"]*)"', xml)
        base = os.path.dirname(os.path.abspath(path))
        absdir = os.path.join(base, meshdir.group(1) if meshdir else "")
        xml = re.sub(r'<compiler ([^>]*?)/>', lambda m: "<compiler " + re.sub(r'\s*meshdir="[^"]*"', "", m.group(1))
                     + f' meshdir="{absdir}" fitaabb="true"/>', xml, count=1)
    xml = re.sub(r'<geom[^>]*type="mesh"[^>]*/>', "", xml)
    used = set(re.findall(r'<geom[^>]*mesh="([^"]+)"', xml))
    xml = re.sub(r'<mesh [^>]*/>', lambda m: m.group(0) if re.search(r'name="([^"]+)"', m.group(0)).group(1) in used
                 else "", xml)
    xml = re.sub(r'(<geom[^>]*type="cylinder")', r'\1 contype="0" conaffinity="0"', xml)
    return xml


def _scale_vector():
    out = []
    for _, size, scale in OBS_TERMS:
        out += list(np.broadcast_to(np.asarray(scale, float), (size,)))
    return np.asarray(out, np.float32)


def slew_command(xp, command, target, max_accel, posture_rate, height_rate, dt):
    """@p command (6,) one control step of @p dt [s] towards @p target (6,) at the controller's slew limits
    (CommandShaper::update): max_accel (3,) [m/s^2, m/s^2, rad/s^2] on v_x, v_y, w, posture_rate [rad/s]
    on pitch and roll, height_rate [m/s] on the height."""
    rate = xp.asarray([*max_accel, posture_rate, posture_rate, height_rate]) * dt
    return command + xp.clip(target - command, -rate, rate)


def envelope_scales(xp, v, pitch, height, lim):
    """The crouched and bent velocity envelopes' scales of the velocity @p v (..., 3) [m/s, m/s, rad/s] at
    the posture (@p pitch [rad], @p height [m], shape (...)): pmg::CommandShaper::envelopeScales
    (src/controller/commands.cpp), v / s on the envelope's edge when s > 1, 0 where an envelope does not
    act. The velocity is not clamped to the controller's box M = lim["max_velocity"] first: training's
    headroom beyond it (box = max_i |v_i| / M_i > 1) passes upright (f = 0), and any crouch or bend brings
    it inside (the scale is at least about box there: the controller's envelopes lie inside its box); inside
    the box the scales are the controller's. Homogeneous: the scales of v / s are the scales of v over s.
    lim: shape_with_envelopes'. Returns (crouch, bent), shape (...)."""
    M = xp.asarray(lim["max_velocity"])
    t = xp.abs(v)
    box = xp.max(t / M, axis=-1)
    sh, ch = lim["standing_height"], lim["crouched_height"]
    f_c = xp.clip((sh - height) / (sh - ch), 0.0, 1.0) if ch > 0 else 0.0 * height
    m_c = M + xp.expand_dims(f_c, -1) * (xp.asarray(lim["crouched_max_velocity"]) - M)
    crouch = xp.where(f_c > 0.0, (1.0 - f_c) * box + f_c * xp.sum(t / m_c, axis=-1), 0.0)
    bp = lim["bent_pitch"]
    f_b = xp.clip(pitch / bp, 0.0, 1.0) if bp > 0 else 0.0 * pitch
    m_b = M + xp.expand_dims(f_b, -1) * (xp.asarray(lim["bent_max_velocity"]) - M)
    bent = xp.where(f_b > 0.0, xp.max(t / m_b, axis=-1), 0.0)
    return crouch, bent


def shape_with_envelopes(xp, command, goal, since_walk, lim):
    """One tick of the controller's command shaper (CommandShaper::update, src/controller/commands.cpp)
    without its clamping, staleness and upset hold: the walking height floor, the crouched and bent
    velocity envelopes (envelope_scales) on the shaped posture, then the slews. A goal beyond
    max_velocity (training's headroom) is not clamped (envelope_scales).

    command (6,): the shaped command of the last tick (v_x, v_y [m/s], w [rad/s], pitch, roll [rad],
    height [m]; heading frame); goal (6,): the drawn command; since_walk: seconds since the robot was
    last told to walk (goal or shaped velocity not zero; large at the start), counted in ticks of dt
    (the hold ends after round(walking_min_height_hold_s / dt) ticks); lim: dict with dt [s],
    standing_height, crouched_height, bent_pitch, walking_min_height [m or rad, 0 = off],
    walking_min_height_hold_s [s], and (3,) arrays max_velocity, crouched_max_velocity,
    bent_max_velocity, max_acceleration, and posture_rate [rad/s], height_rate [m/s].
    Returns (shaped command (6,), since_walk). xp: numpy or jax.numpy."""
    dt = lim["dt"]
    walking = xp.logical_or(xp.any(goal[:3] != 0.0), xp.any(command[:3] != 0.0))
    since_walk = xp.where(walking, 0.0, since_walk + dt)
    floor = lim["walking_min_height"]
    hold = round(lim["walking_min_height_hold_s"] / dt) * dt + 0.5 * dt  # in ticks: no rounding at the edge
    raise_h = xp.logical_and(floor > 0.0, xp.logical_and(since_walk < hold, goal[5] < floor))
    h_goal = xp.where(raise_h, floor, goal[5])
    crouch, bent = envelope_scales(xp, goal[:3], command[3], command[5], lim)
    scale = xp.maximum(crouch, bent)
    v_goal = xp.where(scale > 1.0, goal[:3] / xp.where(scale > 1.0, scale, 1.0), goal[:3])
    target = xp.concatenate([v_goal, goal[3:5], xp.reshape(h_goal, (1,))])
    return slew_command(xp, command, target, lim["max_acceleration"], lim["posture_rate"], lim["height_rate"],
                        dt), since_walk


COMMAND_AXES = ("vx", "vy", "wz", "pitch", "roll", "height")  # the command's order (6,)


def focus_box(cfg, standing_height):
    """The focus box's bounds (lo (6,), hi (6,)) in COMMAND_AXES order, from EnvConfig.p_focus and
    command_focus (an axis not named: 0, or @p standing_height [m] for the height). Raises ValueError
    naming the field for an unknown axis, a bound that is not two finite numbers LO <= HI, a box
    outside the axis's range, p_focus outside [0, 1], or p_focus > 0 without a box."""
    if not 0.0 <= cfg.p_focus <= 1.0:
        raise ValueError(f"EnvConfig.p_focus = {cfg.p_focus}: expected in [0, 1]")
    if cfg.p_focus > 0 and not cfg.command_focus:
        raise ValueError(f"EnvConfig.p_focus = {cfg.p_focus}: needs a command_focus box (at least one axis)")
    lo = np.array([0.0, 0.0, 0.0, 0.0, 0.0, standing_height])
    hi = lo.copy()
    for axis, bounds in cfg.command_focus.items():
        if axis not in COMMAND_AXES:
            raise ValueError(f"EnvConfig.command_focus: unknown axis {axis!r}; expected one of {COMMAND_AXES}")
        try:
            a, b = (float(x) for x in bounds)
        except (TypeError, ValueError):
            a = b = math.nan
        rlo, rhi = getattr(cfg, axis)
        if not (math.isfinite(a) and math.isfinite(b) and a <= b):
            raise ValueError(f"EnvConfig.command_focus[{axis!r}] = {bounds!r}: expected (LO, HI), finite, LO <= HI")
        if a < rlo - 1e-9 or b > rhi + 1e-9:
            raise ValueError(f"EnvConfig.command_focus[{axis!r}] = ({a}, {b}): expected inside the axis's range "
                             f"EnvConfig.{axis} = ({rlo}, {rhi})")
        i = COMMAND_AXES.index(axis)
        lo[i], hi[i] = a, b
    return lo.astype(np.float32), hi.astype(np.float32)


_LEG_MIRROR = [6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 4, 5]


def motion_action_scale(pmg, js):
    """The "motion" rule's leg action scale (LEG,) [rad per unit action]: 1.2 x the walking clips' largest deviation
    from the standing pose, left/right symmetric, clipped to [0.25, 1.2]."""
    dev = np.zeros(LEG)
    for d in pmg.dynamic:
        if d is not None:
            dev = np.maximum(dev, np.abs(d.q[:, :LEG] - js.q_stand[None, :LEG]).max(0))
    dev = np.maximum(dev, dev[_LEG_MIRROR])
    return np.clip(1.2 * dev, 0.25, 1.2)


def posture_action_scale(pmg, js, ranges):
    """The "posture" rule's leg action scale (LEG,) [rad per unit action]: the larger of motion_action_scale and
    1.2 x each static clip's largest offset from its neutral row (the posture offset PMG eq. 10 adds to the standing
    pose) at values inside @p ranges ({static axis 0 pitch, 1 roll, 2 height: (lo, hi)} [rad, rad, m]; the clip's
    own rows inside the range and the range's ends, interpolated as the generator does), left/right symmetric,
    clipped to [0.25, 2.0]."""
    dev = np.zeros(LEG)
    for s in pmg.static:
        if s is None or s.axis not in ranges:
            continue
        lo, hi = ranges[s.axis]
        values = [v for v in s.values if lo <= v <= hi] + [lo, hi]
        neutral = np.asarray(pg._interp_static(np, s, s.neutral))[:LEG]
        for v in values:
            dev = np.maximum(dev, np.abs(np.asarray(pg._interp_static(np, s, v))[:LEG] - neutral))
    dev = np.maximum(dev, dev[_LEG_MIRROR])
    return np.maximum(motion_action_scale(pmg, js), np.clip(1.2 * dev, 0.25, 2.0))


class G1PmgEnv(Env):
    def __init__(self, cfg: EnvConfig, clip_files=None, action_scale=None):
        """@p clip_files: a clip folder or a list of clip files (consistency_map.yaml among them or
        beside them is the consistency map); None = cfg.clips. Read from the files here."""
        if cfg.mode not in ("pmg_gco", "pmg", "single_gait"):
            raise ValueError(f"EnvConfig.mode = {cfg.mode!r}: expected 'pmg_gco', 'pmg' or 'single_gait'")
        if cfg.sole_levelling and cfg.mode != "pmg_gco":
            raise ValueError(f"EnvConfig.sole_levelling: needs mode 'pmg_gco' (it runs with GCO), got {cfg.mode!r}")
        if cfg.stride_adaptation and cfg.mode != "pmg_gco":
            raise ValueError(f"EnvConfig.stride_adaptation: needs mode 'pmg_gco' (it runs with GCO), got {cfg.mode!r}")
        if cfg.upright_walking and cfg.mode == "single_gait":
            raise ValueError("EnvConfig.upright_walking: not with mode 'single_gait' (the Table I baseline)")
        if cfg.blending not in pg.BLENDINGS:
            raise ValueError(f"EnvConfig.blending = {cfg.blending!r}: expected one of {pg.BLENDINGS}")
        if cfg.gains not in GAINS:
            raise ValueError(f"EnvConfig.gains = {cfg.gains!r}: expected one of {GAINS}")
        if not (0.0 <= cfg.actuator_dr < 1.0):
            raise ValueError(f"EnvConfig.actuator_dr = {cfg.actuator_dr}: expected a relative half-width in [0, 1)")
        if not (0.0 <= cfg.actuator_dr_min <= cfg.actuator_dr_max < 1.0) or not cfg.actuator_dr_z >= 0.0:
            raise ValueError(f"EnvConfig.actuator_dr_min/max/z = {cfg.actuator_dr_min}/{cfg.actuator_dr_max}/"
                             f"{cfg.actuator_dr_z}: expected 0 <= min <= max < 1 and z >= 0")
        if cfg.action_offset not in ("default", "reference"):
            raise ValueError(f"EnvConfig.action_offset = {cfg.action_offset!r}: expected 'default' or 'reference'")
        if cfg.pd_damping not in ("implicit", "explicit"):
            raise ValueError(f"EnvConfig.pd_damping = {cfg.pd_damping!r}: expected 'implicit' or 'explicit'")
        self.cfg = cfg
        self.js = pg.joint_space_from_robot_yaml(cfg.robot_yaml)
        self.focus_lo, self.focus_hi = focus_box(cfg, self.js.standing_base_height)
        if clip_files is None:
            clip_files = cfg.clips
        if isinstance(clip_files, str):
            import glob
            import os
            if not os.path.isdir(clip_files):
                raise FileNotFoundError(f"EnvConfig.clips = {clip_files!r}: not a clip folder")
            clip_files = sorted(glob.glob(os.path.join(clip_files, "*.yaml")))
        if cfg.mode == "single_gait":
            clip_files = [f for f in clip_files if f.endswith("walk_forward.yaml")]
            if len(clip_files) != 1:
                raise ValueError("single_gait: needs exactly one walk_forward.yaml among the clips")
            self.pmg = pg.GeneratorModel([pg.load_clip_file(clip_files[0])], [], self.js, blending="paper")
            self.pmg.clip_files, self.pmg.map_file = list(clip_files), None
        else:
            self.pmg = pg.load_library(list(clip_files), self.js, blending=cfg.blending,
                                       upright_walking=cfg.upright_walking)
        self.clip_files = list(self.pmg.clip_files)  # the clips (not the consistency map)
        if cfg.command_envelopes:
            if not cfg.command_slew:
                raise ValueError("EnvConfig.command_envelopes: needs command_slew (the envelopes act on the shaped command)")
            squat = self.pmg.static[2]
            self.envelope_limits = dict(
                dt=cfg.control_dt, standing_height=float(squat.neutral if squat is not None else self.js.standing_base_height),
                max_velocity=tuple(cfg.envelope_max_velocity), crouched_height=cfg.crouched_height,
                crouched_max_velocity=tuple(cfg.crouched_max_velocity), bent_pitch=cfg.bent_pitch,
                bent_max_velocity=tuple(cfg.bent_max_velocity), walking_min_height=cfg.walking_min_height,
                walking_min_height_hold_s=cfg.walking_min_height_hold_s, max_acceleration=tuple(cfg.command_max_accel),
                posture_rate=cfg.command_posture_rate, height_rate=cfg.command_height_rate)
        self.consistency_map_file = self.pmg.map_file
        import yaml
        with open(cfg.robot_yaml) as f:
            joints = yaml.safe_load(f)["joints"]
        self.joint_names = [j["name"] for j in joints]
        if cfg.gains == "physically_informed":
            kp, kd, inertia = gains_mod.pig_gains(self.joint_names)
            self.kp, self.kd = np.array(kp, np.float32), np.array(kd, np.float32)
            self.armature = np.array(inertia, np.float64)
        else:
            self.kp = np.array([j["kp"] for j in joints], np.float32)
            self.kd = np.array([j["kd"] for j in joints], np.float32)
            self.armature = np.full(len(joints), NOMINAL_ARMATURE, np.float64)
        self.tau_max = np.array([j["torque_limit"] for j in joints], np.float32)
        self.q_lower = np.array([j["lower"] for j in joints], np.float32)
        self.q_upper = np.array([j["upper"] for j in joints], np.float32)
        self._setup_actuators(cfg)
        self.q_default = np.asarray(self.js.q_stand, np.float32)
        # Single gait: the generator always runs the forward clip at its nominal speed.
        self.single_gait_ud = np.array([self.pmg.dynamic[0].nominal_scale, 0.0, 0.0], np.float32)
        if cfg.mode == "pmg_gco":
            self.gco_chains, self.gco_opt = gco_port.load_model(cfg.gco_model)

        if action_scale is None:
            if cfg.action_scale_rule not in ("motion", "torque_matched", "posture"):
                raise ValueError(f"EnvConfig.action_scale_rule = {cfg.action_scale_rule!r}: expected 'motion', "
                                 "'torque_matched' or 'posture'")
            if cfg.action_scale_rule == "posture":
                ranges = {0: cfg.pitch, 1: cfg.roll, 2: cfg.height}
                action_scale = posture_action_scale(self.pmg, self.js, ranges)
            else:
                action_scale = motion_action_scale(self.pmg, self.js)
            if cfg.action_scale_rule == "torque_matched":
                kp_nominal = np.array([j["kp"] for j in joints[:LEG]], np.float64)
                action_scale = action_scale * kp_nominal / self.kp[:LEG]
        self.action_scale = np.asarray(action_scale, np.float32)

        mj = mujoco.MjModel.from_xml_string(mjx_friendly_mjcf(cfg.mjcf, leg_collisions=cfg.leg_collisions))
        mj.opt.timestep = cfg.sim_dt
        mj.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER  # joint damping (incl. PD kd) implicit
        mj.dof_armature[6:] = self.armature
        mj.dof_frictionloss[6:] = MODEL_FRICTIONLOSS
        # The PD's D term, integrated implicitly (EnvConfig.pd_damping "implicit"), else only the joints' own.
        mj.dof_damping[6:] = 0.05 + (self.kd if cfg.pd_damping == "implicit" else 0.0)
        if self.act_idx.size and cfg.pd_damping == "explicit":
            raise ValueError("EnvConfig.pd_damping = 'explicit' with identified actuator models (EnvConfig.actuators): "
                             "their D term stays implicit (module docstring)")
        if self.act_idx.size:  # identified joints: their armature and model friction (the step sets them per episode)
            v = 6 + self.act_idx
            c = self.act_center
            mj.dof_armature[v] = np.where(self.act_has_armature, c["armature_kgm2"], mj.dof_armature[v])
            mj.dof_frictionloss[v] = np.maximum(np.maximum(c["fc_Nm"], c["fs_Nm"]), FRICTIONLOSS_FLOOR)
            mj.dof_damping[v] = 0.05 + c["kt_scale"] * c["kd_scale"] * self.kd[self.act_idx] + c["fv_Nms_per_rad"]
        if cfg.joint_stop_timeconst > 0:
            if cfg.joint_stop_timeconst < 2 * cfg.sim_dt - 1e-12:
                raise ValueError(f"EnvConfig.joint_stop_timeconst = {cfg.joint_stop_timeconst}: expected >= 2 sim_dt "
                                 f"({2 * cfg.sim_dt} s)")
            hinges = mj.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
            mj.jnt_solref[hinges, 0] = cfg.joint_stop_timeconst
            mj.jnt_solref[hinges, 1] = 1.0
        mj.opt.iterations = 4
        mj.opt.ls_iterations = 8
        self.mj_model = mj
        # One physics step, (sys, data) -> data: MJX's. eval_mjx.py --physics mujoco puts MuJoCo's C engine
        # (mj_step on mj_model) here to tell the two engines apart.
        self.physics_step = mjx.step
        self.sys = mjx.put_model(mj)
        self.n_substeps = int(round(cfg.control_dt / cfg.sim_dt))
        self.torso_body = mj.body("torso_link").id
        self.pelvis_body = mj.body("pelvis").id
        self.foot_bodies = np.array([mj.body(f"{side}_ankle_roll_link").id for side in ("left", "right")])
        foot_geoms = []
        for b in self.foot_bodies:
            foot_geoms.append([g for g in range(mj.ngeom) if mj.geom_bodyid[g] == b and mj.geom_contype[g] != 0])
        self.foot_geoms = foot_geoms
        # The sole spheres (the feet's floor contacts): the reference-pose reset puts the lowest on the floor.
        spheres = [g for geoms in foot_geoms for g in geoms if mj.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE]
        if len(spheres) < 2:
            raise ValueError(f"{cfg.mjcf}: expected sphere collision geoms on both ankle_roll_links, found {len(spheres)}")
        self.sole_spheres = np.array(spheres)
        self.sole_radius = mj.geom_size[spheres, 0].astype(np.float32)
        self.floor_geom = mj.geom("floor").id
        self.obs_scale = _scale_vector()
        self.arm_idx = np.arange(ARM0, ARM0 + ARM)
        self.hand_bodies = [mj.body(f"{side}_wrist_yaw_link").id for side in ("left", "right")]
        lower = np.array([j["lower"] for j in joints])[self.arm_idx]
        upper = np.array([j["upper"] for j in joints])[self.arm_idx]
        self.arm_lower, self.arm_upper = lower.astype(np.float32), upper.astype(np.float32)
        self.arm_default = self.q_default[self.arm_idx]
        self._setup_upper_body(mj, cfg)

    def _setup_upper_body(self, mj, cfg):
        """Constants of the waist gravity compensation (EnvConfig.upper_body_ff): the waist joints' ids,
        dof indices and bodies, each joint's subtree as a 0/1 mask over bodies (3, nbody) and the nominal
        body masses, the torque bound per joint."""
        if not (0.0 <= cfg.upper_body_damping <= 50.0 and 0.0 < cfg.upper_body_max_torque <= 200.0):
            raise ValueError(f"EnvConfig.upper_body_damping / upper_body_max_torque = {cfg.upper_body_damping} / "
                             f"{cfg.upper_body_max_torque}: expected 0..50 N m s/rad and (0, 200] N m")
        names = ("waist_yaw_joint", "waist_roll_joint", "waist_pitch_joint")
        self.ub_jnt = np.array([mj.joint(n).id for n in names], np.int32)
        self.ub_dof = np.array([mj.jnt_dofadr[j] for j in self.ub_jnt], np.int32)
        self.ub_q = np.array([self.joint_names.index(n) for n in names], np.int32)  # robot order (ctrl, kp)
        roots = [mj.jnt_bodyid[j] for j in self.ub_jnt]
        mask = np.zeros((len(names), mj.nbody))
        for r, root in enumerate(roots):
            for b in range(mj.nbody):
                a = b
                while a != 0 and a != root:
                    a = mj.body_parentid[a]
                mask[r, b] = 1.0 if a == root else 0.0
        self.ub_mask = mask
        self.ub_mass = np.asarray(mj.body_mass, np.float64).copy()
        self.ub_limit = np.minimum(cfg.upper_body_max_torque, self.tau_max[self.ub_q]).astype(np.float32)
        if cfg.upper_body_ff and np.isin(self.ub_q, self.act_idx).any():
            # The identified actuator model replaces those joints' torque with its own PD (no tau_ff term).
            raise ValueError(f"EnvConfig.upper_body_ff with EnvConfig.actuators = {cfg.actuators!r}: that config "
                             "identifies a waist joint, and the actuator model's torque has no feed-forward term; "
                             "use one or the other")

    def waist_gravity(self, xipos, xanchor, xaxis):
        """Gravity torque [N m] that holds each waist joint (yaw, roll, pitch), (3,): for the hinge with
        world anchor p and axis a, a . ((c - p) x (M g_up)), with M the nominal mass beyond the joint, c
        its centre of mass (frame W) and g_up = (0, 0, 9.81) m/s^2; = MuJoCo's qfrc_bias at zero
        velocity on those dofs (smoke check 1f). @p xipos (nbody, 3), xanchor / xaxis (njnt, 3): a data's
        kinematics. Works on NumPy and JAX arrays."""
        xp = jnp if isinstance(xipos, jax.Array) else np
        m = xp.asarray(self.ub_mask * self.ub_mass[None, :], dtype=xipos.dtype)
        M = m.sum(axis=1)
        c = (m @ xipos) / M[:, None]
        p = xanchor[self.ub_jnt]
        a = xaxis[self.ub_jnt]
        f = xp.stack([xp.zeros_like(M), xp.zeros_like(M), M * 9.81], axis=1)
        return xp.sum(a * xp.cross(c - p, f), axis=1)

    def _setup_actuators(self, cfg):
        """Identified actuator models from cfg.actuators (module docstring "Actuator models"):
        act_idx (joint indices with a block, robot order), act_center (identified values per key,
        (m,) float64), act_has_armature, act_rows (delay-line length)."""
        blocks = load_actuator_blocks(cfg.actuators, self.joint_names) if cfg.actuators else {}
        self.actuator_blocks = blocks
        self.act_idx = np.array([i for i, n in enumerate(self.joint_names) if n in blocks], np.int32)
        m = self.act_idx.size
        self.act_center = {k: np.zeros(m) for k in ACT_KEYS}
        self.act_has_armature = np.zeros(m, bool)
        self.act_randomised = {k: np.zeros(m, bool) for k in ACT_DR_KEYS}
        self.act_dr = {k: np.zeros(m) for k in ACT_DR_KEYS}
        self.act_rows = 2
        if not m:
            return
        ordered = [blocks[self.joint_names[i]] for i in self.act_idx]
        for k in ACT_KEYS:
            self.act_center[k] = np.array([b[k] if b[k] is not None else 0.0 for b in ordered], np.float64)
        self.act_has_armature = np.array([b["armature_kgm2"] is not None for b in ordered])
        # Randomised: the gain scales (pmg_calib_joints fits them on every calibrated joint; a block omits
        # them at 1) and every key the block names; keys it does not name stay at their "off" value.
        named = [set(b["_named"]) for b in ordered]
        self.act_randomised = {k: np.array([k in ("kp_scale", "kd_scale") or k in n for n in named])
                               for k in ACT_DR_KEYS}
        # Relative DR half-widths: sized from the calibration's uncertainty where it gives one.
        for k in ACT_DR_KEYS:
            w = np.full(m, cfg.actuator_dr)
            for r, b in enumerate(ordered):
                u = b["_uncertainty"].get(k)
                if u is not None:
                    value = abs(float(self.act_center[k][r]))
                    rel = cfg.actuator_dr_z * u / value if value > 0 else cfg.actuator_dr_max
                    w[r] = min(max(rel, cfg.actuator_dr_min), cfg.actuator_dr_max)
            self.act_dr[k] = np.where(self.act_randomised[k], w, 0.0)
        # A block that names no dry friction keeps the model's joint friction, as the SIL does
        # (pmg::MujocoBackend::setActuatorBlock): a block changes only what it names.
        no_dry = np.array([not ({"fc_Nm", "fs_Nm", "kl"} & n) for n in named])
        self.act_center["fc_Nm"] = np.where(no_dry, MODEL_FRICTIONLOSS, self.act_center["fc_Nm"])
        # Saturation: the block's and the joint's torque limit, whichever is lower (as pmg::MujocoBackend).
        self.act_center["torque_limit_Nm"] = np.minimum(self.act_center["torque_limit_Nm"],
                                                        self.tau_max[self.act_idx].astype(np.float64))
        max_delay = float(np.max(self.act_center["delay_s"] * (1.0 + self.act_dr["delay_s"])))
        self.act_rows = int(math.ceil(max_delay / cfg.sim_dt)) + 2
        slow = [n for n, b in zip((self.joint_names[i] for i in self.act_idx), ordered)
                if 0 < b["rate_hz"] < 1.0 / cfg.sim_dt]
        if slow:
            print(f"g1_env: {cfg.actuators}: rate_hz below the {1.0 / cfg.sim_dt:g} Hz physics rate on {slow}: the "
                  f"driver's zero-order hold is not modelled in training (the PD is recomputed every physics step)")

    def _draw_actuators(self, rng):
        """Identified actuator parameters of one episode, (m,) each: value x U(1 - dr, 1 + dr) per
        joint and key (ACT_DR_KEYS, dr = act_dr[key]), the identified values with deterministic_reset."""
        c = self.cfg
        m = self.act_idx.size
        draw = {}
        keys = jax.random.split(rng, len(ACT_KEYS))
        for key, k in zip(ACT_KEYS, keys):
            centre = jnp.asarray(self.act_center[key], jnp.float32)
            if key in ACT_DR_KEYS and not c.deterministic_reset:
                dr = jnp.asarray(self.act_dr[key], jnp.float32)
                centre = centre * jax.random.uniform(k, (m,), minval=1.0 - dr, maxval=1.0 + dr)
            draw[key] = centre
        draw["kt_scale"] = jnp.clip(draw["kt_scale"], 1e-3, 5.0)
        draw["kl"] = jnp.clip(draw["kl"], 0.0, 0.99)
        draw["delay_s"] = jnp.clip(draw["delay_s"], 0.0, (self.act_rows - 2) * c.sim_dt)
        draw["torque_limit_Nm"] = jnp.minimum(draw["torque_limit_Nm"], jnp.asarray(self.tau_max[self.act_idx]))
        return draw

    def _act_line_reset(self):
        """An empty delay line for the identified joints (actuator.init_state: the rows it uses)."""
        s = act_port.init_state(self.act_idx.size, self.act_rows, xp=jnp, dtype=jnp.float32)
        return {k: s[k] for k in ("fifo", "fifo_enabled", "head", "count")}

    def actuator_sys(self, sys, draw):
        """@p sys with the identified joints' armature (where identified) and the implicit damping of
        their PD's D term: 0.05 (the SIL's joint damping) + kt_scale kd_scale kd + fv [N m s/rad]."""
        v = 6 + jnp.asarray(self.act_idx)
        kd = jnp.asarray(self.kd[self.act_idx])
        arm = jnp.where(jnp.asarray(self.act_has_armature), draw["armature_kgm2"], sys.dof_armature[v])
        damp = 0.05 + draw["kt_scale"] * draw["kd_scale"] * kd + draw["fv_Nms_per_rad"]
        return sys.replace(dof_armature=sys.dof_armature.at[v].set(arm), dof_damping=sys.dof_damping.at[v].set(damp))

    def actuator_torque(self, draw, line, q_des, qd_des, q, dq):
        """One physics substep of the identified joints' actuator model (module docstring): pushes the
        command (q_des, qd_des at the identified joints, (m,)) into the delay line, runs the delayed
        PD with kp kp_scale, kd kd_scale on the true joint state (q, dq (m,)), scales by kt_scale, limits
        (saturation, torque-speed envelope at dq). Returns (line, tau_motor (m,) [N m] for ctrl, the
        explicit part of the implicit D term, kt kd kd_scale dq (m,) [N m] for qfrc_applied, dry
        friction magnitude (m,) [N m] for dof_frictionloss)."""
        idx = self.act_idx
        kp = jnp.asarray(self.kp[idx]) * draw["kp_scale"]
        kd = jnp.asarray(self.kd[idx]) * draw["kd_scale"]
        m = idx.size
        cmd = {"q_des_rad": q_des, "dq_des_rad_per_s": qd_des, "kp_Nm_per_rad": kp, "kd_Nms_per_rad": kd,
               "tau_ff_Nm": jnp.zeros(m), "enabled": jnp.ones(m, bool)}
        line = act_port.push_command(line, cmd, xp=jnp)
        c, _ = act_port.delayed_command(draw, line, self.cfg.sim_dt, xp=jnp)
        pd = draw["kt_scale"] * (c[2] * (c[0] - q) + c[3] * (c[1] - dq))
        tau_m = act_port.limit_torque(draw, pd, dq, xp=jnp)
        d_explicit = draw["kt_scale"] * kd * dq
        friction = jnp.maximum(act_port.kinetic_friction(draw, dq, tau_m, xp=jnp), FRICTIONLOSS_FLOOR)
        return line, tau_m, d_explicit, friction

    # ---- Brax Env interface ----------------------------------------------------------------
    @property
    def observation_size(self):
        return {"state": (62,), "privileged_state": (62 + 3 + 1 + 2 + 2 + 2 + 2 + ARM + 2,)}

    @property
    def action_size(self):
        return LEG

    @property
    def backend(self):
        return "mjx"

    def _sample_command(self, rng):
        """User command u (6,): v_x, v_y, w, pitch, roll, height (module docstring: command mix)."""
        c = self.cfg
        k = jax.random.split(rng, 10)
        lo = jnp.array([c.vx[0], c.vy[0], c.wz[0]])
        hi = jnp.array([c.vx[1], c.vy[1], c.wz[1]])
        v = jax.random.uniform(k[0], (3,), minval=lo, maxval=hi)
        kind = jax.random.uniform(k[1])
        single = kind < c.p_single_axis
        combined = jnp.logical_and(kind >= c.p_single_axis, kind < c.p_single_axis + c.p_combined)
        axis = jax.random.randint(k[2], (), 0, 3)
        one = jax.nn.one_hot(axis, 3)
        # Combined: all three axes, or two (the one-hot axis dropped) with probability p_two_axes.
        two = jax.random.uniform(k[3]) < c.p_two_axes
        mask = jnp.where(single, one, jnp.where(combined, jnp.where(two, 1.0 - one, 1.0), 0.0))
        v = v * mask
        walking = jnp.logical_or(single, combined)
        plo = jnp.array([c.pitch[0], c.roll[0], c.height[0]])
        phi = jnp.array([c.pitch[1], c.roll[1], c.height[1]])
        posture = jax.random.uniform(k[4], (3,), minval=plo, maxval=phi)
        neutral = jnp.array([0.0, 0.0, self.js.standing_base_height])
        axes = jax.random.uniform(k[5], (3,)) < c.p_posture_axis
        axes = jnp.where(jnp.any(axes), axes, jax.nn.one_hot(jax.random.randint(k[6], (), 0, 3), 3) > 0)
        p_posture = jnp.where(walking, c.p_posture_walk, c.p_posture_stand)
        commanded = jax.random.uniform(k[7]) < p_posture
        posture = jnp.where(jnp.logical_and(commanded, axes), posture, neutral)
        goal = jnp.concatenate([v, posture])
        if c.p_focus > 0:  # EnvConfig.command_focus (off: the stream and the graph as before)
            box = jax.random.uniform(k[8], (6,), minval=self.focus_lo, maxval=self.focus_hi)
            goal = jnp.where(jax.random.uniform(k[9]) < c.p_focus, box, goal)
        return goal

    def _next_command(self, goal, command, since_walk, k_cmd, resample):
        """One control step of the user's command: at a resample a new goal is drawn (a stop after a
        walking goal with probability p_stop), then the command is shaped towards it (command_slew, and
        command_envelopes: shape_with_envelopes). Returns (goal, command, since_walk [s])."""
        c = self.cfg
        new = self._sample_command(k_cmd)
        if c.p_stop > 0:
            walked = jnp.any(goal[:3] != 0.0)
            stop = jnp.logical_and(walked, jax.random.uniform(jax.random.fold_in(k_cmd, 7)) < c.p_stop)
            keep = jax.random.uniform(jax.random.fold_in(k_cmd, 8)) < c.p_stop_keep_posture
            stopped = new.at[:3].set(0.0)
            stopped = jnp.where(keep, stopped.at[3:].set(goal[3:]), stopped)
            new = jnp.where(stop, stopped, new)
        goal = jnp.where(resample, new, goal)
        if c.command_envelopes:
            command, since_walk = shape_with_envelopes(jnp, command, goal, since_walk, self.envelope_limits)
        else:
            command = self._shape_command(command, goal)
        return goal, command, since_walk

    def _first_command(self, goal):
        """The episode's first command for the drawn @p goal: the goal itself, or with command_envelopes
        the goal inside the envelopes and above the walking height floor at once (no slew)."""
        if not self.cfg.command_envelopes:
            return goal
        lim = self.envelope_limits
        floor = lim["walking_min_height"]
        walking = jnp.any(goal[:3] != 0.0)
        height = jnp.where(jnp.logical_and(walking, goal[5] < floor), floor, goal[5]) if floor > 0 else goal[5]
        scale = jnp.maximum(1.0, jnp.maximum(*envelope_scales(jnp, goal[:3], goal[3], height, lim)))
        return jnp.concatenate([goal[:3] / scale, goal[3:5], jnp.reshape(height, (1,))])

    def _shape_command(self, command, goal):
        """The command after one control step towards the drawn goal (EnvConfig.command_slew: slew
        limits per axis, as the controller's command shaper; off: the goal itself)."""
        c = self.cfg
        if not c.command_slew:
            return goal
        return slew_command(jnp, command, goal, c.command_max_accel, c.command_posture_rate, c.command_height_rate,
                            c.control_dt)

    def _reference(self, phase, command, gco_state):
        """Generator (+ GCO) tick as the controller runs it. Returns (ref dict, command the actor
        observes and the rewards track (6,), new GCO state)."""
        c = self.cfg
        if c.mode == "single_gait":
            ref = pg.step(self.pmg, phase, jnp.asarray(self.single_gait_ud), jnp.zeros(3), c.control_dt, xp=jnp)
            return ref, command, gco_state
        ref = pg.step(self.pmg, phase, command[:3], command[3:], c.control_dt, xp=jnp)
        if c.mode == "pmg":
            return ref, command, gco_state
        if c.sole_levelling:
            ref, _, _, gco_state = gco_port.level_soles(self.gco_chains, self.gco_opt, ref, self.js.q_stand,
                                                        self.js.lower, self.js.upper, gco_state, xp=jnp)
        if c.stride_adaptation:
            ref, _, _, gco_state = gco_port.adapt_strides(self.gco_chains, self.gco_opt, ref, command[:3], self.js.lower,
                                                          self.js.upper, gco_state, xp=jnp)
        u_opt, _, _, gco_state = gco_port.step(self.gco_chains, self.gco_opt, ref, command[3:], gco_state, xp=jnp)
        return ref, u_opt.astype(jnp.float32), gco_state

    def _height_target(self, command):
        """Pelvis height the reward tracks: the user's commanded height (all modes)."""
        return jnp.asarray(command[5], jnp.float32)

    # ---- teleoperated arms (module docstring) -----------------------------------------------
    def _sample_arm_goals(self, rng, goal):
        """Next waypoints of both arms (14,) [rad], within the joint limits. An arm keeps its
        current goal @p goal with probability 0.2 (one arm moves alone), except when carrying."""
        c = self.cfg
        k = jax.random.split(rng, 6)
        mirror = jnp.asarray(MIRROR_SIGN, jnp.float32)
        lo, hi = jnp.asarray(TELEOP_LO, jnp.float32), jnp.asarray(TELEOP_HI, jnp.float32)
        left = jax.random.uniform(k[0], (7,), minval=lo, maxval=hi)
        right = mirror * jax.random.uniform(k[1], (7,), minval=lo, maxval=hi)
        clo, chi = jnp.asarray(TELEOP_CARRY_LO, jnp.float32), jnp.asarray(TELEOP_CARRY_HI, jnp.float32)
        carry_left = jax.random.uniform(k[2], (7,), minval=clo, maxval=chi)
        carry_right = mirror * (carry_left + jax.random.uniform(k[3], (7,), minval=-0.1, maxval=0.1))
        carry = jax.random.uniform(k[4]) < c.p_teleop_carry
        new = jnp.where(carry, jnp.concatenate([carry_left, carry_right]), jnp.concatenate([left, right]))
        keep = jnp.logical_and(jax.random.uniform(k[5], (2,)) < 0.2, jnp.logical_not(carry))
        new = jnp.where(jnp.repeat(keep, 7), goal, new)
        return jnp.clip(new, jnp.asarray(self.arm_lower), jnp.asarray(self.arm_upper))

    def _teleop_flags(self, rng):
        """Which arms teleop drives in the next segment (2,) in {0, 1}."""
        k = jax.random.split(rng, 2)
        on = jax.random.uniform(k[0]) < self.cfg.p_teleop
        arms = jnp.logical_and(on, jax.random.uniform(k[1], (2,)) < self.cfg.p_teleop_arm)
        return arms.astype(jnp.float32)

    def _hand_forces(self, rng, arms_on):
        """Target external forces of both hands for the next segment (2, 3) [N], world frame
        (EnvConfig.p_hand_force, hand_force_z, hand_force_xy); zero for a hand teleop does not drive."""
        c = self.cfg
        k = jax.random.split(rng, 4)
        on = jnp.logical_and(arms_on > 0, jax.random.uniform(k[0], (2,)) < c.p_hand_force)
        ang = jax.random.uniform(k[1], (2,), minval=0.0, maxval=2 * math.pi)
        mag = jax.random.uniform(k[2], (2,), minval=0.0, maxval=c.hand_force_xy)
        fz = jax.random.uniform(k[3], (2,), minval=c.hand_force_z[0], maxval=c.hand_force_z[1])
        f = jnp.stack([mag * jnp.cos(ang), mag * jnp.sin(ang), fz], axis=1)
        return jnp.where(on[:, None], f, 0.0)

    def _teleop_advance(self, info, rng):
        """One control period of the teleop arm targets: waypoint timer, straight-line motion at
        the waypoint's speed (largest joint speed), PMG/teleop blend weights. Updates info."""
        c = self.cfg
        k = jax.random.split(rng, 3)
        timer = info["tp_timer"] - 1
        new_wp = timer <= 0
        goal = jnp.where(new_wp, self._sample_arm_goals(k[0], info["tp_goal"]), info["tp_goal"])
        speed = jnp.where(new_wp, jax.random.uniform(k[1], (), minval=c.teleop_speed[0], maxval=c.teleop_speed[1]),
                          info["tp_speed"])
        hold = jax.random.uniform(k[2], (), minval=c.teleop_hold[0], maxval=c.teleop_hold[1])
        timer = jnp.where(new_wp, jnp.round(hold / c.control_dt).astype(jnp.int32), timer)
        delta = (goal - info["tp_tgt"]).reshape(2, 7)
        largest = jnp.max(jnp.abs(delta), axis=1, keepdims=True)
        move = delta * jnp.minimum(1.0, speed * c.control_dt / jnp.maximum(largest, 1e-6))
        info["tp_tgt"] = info["tp_tgt"] + move.reshape(ARM)
        info["tp_vel"] = move.reshape(ARM) / c.control_dt
        info["tp_goal"], info["tp_speed"], info["tp_timer"] = goal, speed, timer
        rate = c.teleop_blend_rate * c.control_dt
        info["tp_w"] = info["tp_w"] + jnp.clip(info["tp_on"] - info["tp_w"], -rate, rate)
        return info

    def reset(self, rng):
        c = self.cfg
        k = jax.random.split(rng, 16)
        qpos = jnp.asarray(self.mj_model.qpos0).at[7:].set(self.q_default)
        qpos = qpos.at[2].set(0.79)
        joint_noise = (jnp.zeros(29) if c.deterministic_reset else
                       jax.random.uniform(k[0], (29,), minval=-0.05, maxval=0.05))
        qpos = qpos.at[7:].add(joint_noise)
        info = {
            "rng": k[1],
            "step": jnp.zeros((), jnp.int32),
            "phase": jnp.float32(0.0) if c.deterministic_reset else jax.random.uniform(k[2]),
            "command": self._sample_command(k[3]),
            "last_action": jnp.zeros(LEG),
            "prev_action": jnp.zeros(LEG),
            "kp_scale": jnp.float32(1.0) if c.deterministic_reset else
                        jax.random.uniform(k[4], (), minval=c.kp_scale[0], maxval=c.kp_scale[1]),
            "delay": jnp.float32(0.0) if c.deterministic_reset else
                     (jax.random.uniform(k[5]) < c.p_delay).astype(jnp.float32),
            "arm_amp": jax.random.uniform(k[6], (14,), minval=0.0, maxval=c.arm_perturb) *
                       (jax.random.uniform(k[7]) < 0.7),
            "arm_freq": jax.random.uniform(k[8], (14,), minval=0.2, maxval=1.0),
            "arm_off": jax.random.uniform(k[9], (14,), minval=0.0, maxval=2 * math.pi),
            # Teleop arm targets: start at the default arm pose, first waypoint within 1 s.
            "tp_tgt": jnp.asarray(self.arm_default),
            "tp_vel": jnp.zeros(ARM),
            "tp_goal": jnp.asarray(self.arm_default),
            "tp_speed": jnp.float32(1.0),
            "tp_timer": jax.random.randint(k[11], (), 1, int(round(1.0 / c.control_dt)) + 1),
            "tp_on": self._teleop_flags(k[12]),
            "tp_w": jnp.zeros(2),
            "push_timer": self._push_interval(k[13]),
            "hf_tgt": jnp.zeros((2, 3)),   # external hand forces (target, applied) [N], world frame (below)
            "hf": jnp.zeros((2, 3)),
        }
        info["command_goal"] = info["command"]  # the drawn command (command_slew: what "command" moves to)
        info["since_walk"] = jnp.float32(1e3)  # [s] since last told to walk (command_envelopes)
        info["command"] = self._first_command(info["command_goal"])
        if c.p_hand_force > 0:
            info["hf_tgt"] = self._hand_forces(k[15], info["tp_on"])
        if self.act_idx.size:
            info["act"] = self._draw_actuators(k[14])
            info["act_line"] = self._act_line_reset()
        ref, tracked, info["gco"] = self._reference(info["phase"], info["command"],
                                                    jax.tree_util.tree_map(lambda x: jnp.asarray(x, jnp.float32)
                                                                           if x.dtype != bool else x,
                                                                           gco_port.initial_state(xp=jnp)))
        info["tracked"] = jnp.asarray(tracked, jnp.float32)
        info["ref_q"] = ref["q_ref"].astype(jnp.float32)
        info["ref_qd"] = ref["qd_ref"].astype(jnp.float32)
        info["ref_contact"] = ref["in_contact"].astype(jnp.float32)
        info["ref_height"] = self._height_target(info["command"])
        info["next_phase"] = jnp.asarray(ref["next_phase"], jnp.float32)
        info["measured"] = jnp.zeros(8)
        info["arm_des_rel"] = info["ref_q"][ARM0:] - jnp.asarray(self.arm_default)
        if c.p_reset_reference > 0:
            # Under vmap both candidates are computed, so the pose is chosen before the one forward pass
            # (with two, V20b compiled about 50 s longer per stage on an H200 host than V20a without reference
            # starts; on the CPU, 57 s against 40 s for jit(vmap(reset)) with one).
            use = jax.random.uniform(jax.random.fold_in(k[15], 1)) < c.p_reset_reference
            qpos = jnp.where(use, self._reference_qpos(qpos, info["ref_q"] + joint_noise), qpos)
        data = mjx.forward(self.sys, mjx.make_data(self.sys).replace(qpos=qpos, qvel=jnp.zeros(self.mj_model.nv)))
        obs = self._obs(data, info, k[10])
        metrics = {n: jnp.zeros(()) for n in ["lin_vel_err", "yaw_rate_err", "pitch_err", "roll_err", "height_err",
                                              "ref_q_err", "contact_match", "energy", "foot_slip"]
                   + [f"reward_{t}" for t in REWARD_TERMS]}
        return State(data, obs, jnp.zeros(()), jnp.zeros(()), metrics, info)

    def _reference_qpos(self, qpos, q):
        """Generalised position (nq,) of the standing @p qpos with joint pose @p q (29,) [rad] (clipped to
        the joint limits), the pelvis upright at the same place in x, y, lowered or raised so that the lowest
        sole sphere touches the floor (world z = 0). One kinematics pass, no forward pass."""
        qpos = qpos.at[7:].set(jnp.clip(q, self.q_lower, self.q_upper))
        kin = mjx.kinematics(self.sys, mjx.make_data(self.sys).replace(qpos=qpos))
        bottom = jnp.min(kin.geom_xpos[self.sole_spheres, 2] - self.sole_radius)
        return qpos.at[2].add(-bottom)

    def hold_action(self, ref_q_legs):
        """The action (12,) whose leg PD targets are @p ref_q_legs (12,) [rad], within the action range
        [-1, 1]: zero with residual actions (action_offset "reference"), else (ref_q - standing pose) /
        action_scale. The inverse of step()'s target q_des = offset + action_scale x action."""
        if self.cfg.action_offset == "reference":
            return jnp.zeros(LEG)
        return jnp.clip((ref_q_legs - jnp.asarray(self.q_default[:LEG])) / jnp.asarray(self.action_scale), -1.0, 1.0)

    def step(self, state: State, action):
        c = self.cfg
        info = dict(state.info)
        rng, k_noise, k_cmd, k_arm, k_seg, k_push = jax.random.split(info["rng"], 6)
        info["rng"] = rng
        info = self._teleop_advance(info, k_arm)
        a = jnp.clip(action, -1.0, 1.0)
        applied = jnp.where(info["delay"] > 0, info["last_action"], a)  # one period of latency
        q_des = jnp.asarray(self.q_default)
        base = info["ref_q"][:LEG] if c.action_offset == "reference" else jnp.asarray(self.q_default[:LEG])
        q_des = q_des.at[:LEG].set(base + jnp.asarray(self.action_scale) * applied)
        if c.clamp_targets:
            q_des = q_des.at[:LEG].set(jnp.clip(q_des[:LEG], self.q_lower[:LEG], self.q_upper[:LEG]))
        t = info["step"].astype(jnp.float32) * c.control_dt
        arm_pert = info["arm_amp"] * jnp.sin(2 * math.pi * info["arm_freq"] * t + info["arm_off"])
        q_des = q_des.at[LEG:].set(info["ref_q"][LEG:])
        q_des = q_des.at[ARM0:].add(arm_pert)
        qd_des = jnp.zeros(29).at[LEG:].set(info["ref_qd"][LEG:])
        # Teleoperated arms: blend from the PMG target to the teleop target (absolute joint angles).
        w = jnp.repeat(info["tp_w"], 7)
        q_des = q_des.at[ARM0:].set((1 - w) * q_des[ARM0:] + w * info["tp_tgt"])
        qd_des = qd_des.at[ARM0:].set((1 - w) * qd_des[ARM0:] + w * info["tp_vel"])
        arm_des_rel = q_des[ARM0:] - jnp.asarray(self.arm_default)
        kp = jnp.asarray(self.kp) * info["kp_scale"]
        kd = jnp.asarray(self.kd)

        ident = self.act_idx.size > 0
        sys = self.sys
        if ident:
            idx = jnp.asarray(self.act_idx)
            v = 6 + idx
            sys = self.actuator_sys(sys, info["act"])

        tau_ff = jnp.zeros(29)
        if c.upper_body_ff:  # the controller's upper_body: feed-forward, once per tick (EnvConfig.upper_body_ff)
            d0 = state.pipeline_state
            ff = self.waist_gravity(d0.xipos, d0.xanchor, d0.xaxis) - c.upper_body_damping * d0.qvel[self.ub_dof]
            lim = jnp.asarray(self.ub_limit)
            tau_ff = tau_ff.at[self.ub_q].set(jnp.clip(ff, -lim, lim))

        def substep(carry, _):
            data, line = carry
            q = data.qpos[7:]
            if c.pd_damping == "explicit":
                tau = kp * (q_des - q) + kd * (qd_des - data.qvel[6:]) + tau_ff
            else:
                tau = kp * (q_des - q) + kd * qd_des + tau_ff  # -kd*qd is the implicit joint damping
            tau = jnp.clip(tau, -self.tau_max, self.tau_max)
            sys_k = sys
            if ident:
                line, tau_m, d_explicit, friction = self.actuator_torque(
                    info["act"], line, q_des[idx], qd_des[idx], q[idx], data.qvel[v])
                tau = tau.at[idx].set(tau_m)
                # The implicit damping (dof_damping) takes -c dq_next; adding c dq here leaves the model's
                # explicit torque, saturation included, plus the stabilising implicit -c (dq_next - dq).
                data = data.replace(qfrc_applied=jnp.zeros_like(data.qfrc_applied).at[v].set(d_explicit))
                sys_k = sys.replace(dof_frictionloss=sys.dof_frictionloss.at[v].set(friction))
            data = data.replace(ctrl=tau)
            return (self.physics_step(sys_k, data), line), tau

        data = state.pipeline_state
        if c.p_hand_force > 0:
            rate = c.hand_force_rate * c.control_dt
            goal = info["hf_tgt"] * info["tp_w"][:, None]
            info["hf"] = info["hf"] + jnp.clip(goal - info["hf"], -rate, rate)
            xfrc = jnp.zeros_like(data.xfrc_applied).at[jnp.asarray(self.hand_bodies), :3].set(info["hf"])
            data = data.replace(xfrc_applied=xfrc)
        if not c.deterministic_reset and c.push_vel[1] > 0:
            data, info["push_timer"] = self._push(data, info["push_timer"], k_push)
        foot_xy_start = data.xpos[self.foot_bodies, :2]  # ankle_roll_link origins, world x, y [m]
        (data, line), taus = jax.lax.scan(substep, (data, info.get("act_line")), None, length=self.n_substeps)
        if ident:
            info["act_line"] = line
        tau = taus[-1]

        # PMG, as the controller runs it: one generator step per control tick, evaluated at the
        # phase the previous step advanced to (eq. 11).
        phase = info["next_phase"]
        info["step"] = info["step"] + 1
        resample = (info["step"] % c.command_resample) == 0
        user_prev = info["command"]  # the user's command u when the actor chose this action
        info["command_goal"], info["command"], info["since_walk"] = self._next_command(
            info["command_goal"], info["command"], info["since_walk"], k_cmd, resample)
        info["tp_on"] = jnp.where(resample, self._teleop_flags(k_seg), info["tp_on"])
        if c.p_hand_force > 0:
            info["hf_tgt"] = jnp.where(resample, self._hand_forces(jax.random.fold_in(k_seg, 1), info["tp_on"]),
                                       info["hf_tgt"])
        ref_prev_contact = info["ref_contact"]
        ref, tracked, info["gco"] = self._reference(phase, info["command"], info["gco"])
        info["phase"] = phase

        # Measurements.
        R = _quat_to_rot(data.qpos[3:7])
        yaw = jnp.arctan2(R[1, 0], R[0, 0])
        cy, sy = jnp.cos(yaw), jnp.sin(yaw)
        v_W = data.qvel[0:3]
        v_H = jnp.array([cy * v_W[0] + sy * v_W[1], -sy * v_W[0] + cy * v_W[1], v_W[2]])
        w_W = R @ data.qvel[3:6]
        R_torso = data.xmat[self.torso_body].reshape(3, 3)
        pitch, roll = _pitch_roll(R_torso)
        height = data.qpos[2]
        contact = self._foot_contacts(data)

        # Task rewards track the user's command u (not u'; module docstring).
        cmd = user_prev
        lin_err = jnp.sum((cmd[:2] - v_H[:2]) ** 2)
        yaw_err = (cmd[2] - w_W[2]) ** 2
        ori_err = (cmd[3] - pitch) ** 2 + (cmd[4] - roll) ** 2
        h_err = (info["ref_height"] - height) ** 2
        q = data.qpos[7:7 + LEG]
        qd = data.qvel[6:6 + LEG]
        ref_q_err = jnp.sum((q - info["ref_q"][:LEG]) ** 2)
        ref_qd_err = jnp.sum((qd - info["ref_qd"][:LEG]) ** 2)
        contact_match = jnp.mean((contact == ref_prev_contact).astype(jnp.float32))
        # Foot slip [m/s]: the horizontal speed of each ankle_roll_link origin over this control step,
        # summed over the feet that touch the floor at its end (pmg_policy_sil's and eval_mjx's foot_slip).
        foot_speed = jnp.linalg.norm(data.xpos[self.foot_bodies, :2] - foot_xy_start, axis=-1) / c.control_dt
        foot_slip = jnp.sum(contact * foot_speed)
        energy = jnp.sum(jnp.abs(tau[:LEG] * qd))
        action_rate = jnp.sum((a - info["last_action"]) ** 2)
        R_up = R[2, 2]
        done = jnp.logical_or(height < 0.4, R_up < 0.5)
        done = jnp.logical_or(done, jnp.logical_not(jnp.all(jnp.isfinite(data.qpos))))
        w = c.w
        terms = {"lin_vel": w["lin_vel"] * jnp.exp(-lin_err / c.lin_vel_sigma),
                 "yaw_rate": w["yaw_rate"] * jnp.exp(-yaw_err / c.yaw_rate_sigma),
                 "orientation": w["orientation"] * jnp.exp(-ori_err / c.orientation_sigma),
                 "height": w["height"] * jnp.exp(-h_err / c.height_sigma),
                 "ref_q": w["ref_q"] * jnp.exp(-ref_q_err / 0.5), "ref_qd": w["ref_qd"] * jnp.exp(-ref_qd_err / 50.0),
                 "contact": w["contact"] * contact_match, "energy": w["energy"] * energy,
                 "action_rate": w["action_rate"] * action_rate, "alive": jnp.float32(w["alive"]),
                 "termination": w["termination"] * done}
        # The optional terms (OPTIONAL_REWARD_TERMS, unweighted values in its order) enter the reward only with a
        # weight; configs saved before a term have no entry.
        unweighted = (foot_slip, jnp.sqrt(lin_err), jnp.sqrt(yaw_err), jnp.all(contact < 0.5).astype(jnp.float32))
        for name, value in zip(OPTIONAL_REWARD_TERMS, unweighted):
            if w.get(name, 0.0) != 0.0:
                terms[name] = w[name] * value
        reward = functools.reduce(jnp.add, terms.values())
        reward = jnp.where(jnp.isfinite(reward), reward, 0.0)

        info["prev_action"] = info["last_action"]
        info["last_action"] = a
        info["ref_q"] = ref["q_ref"].astype(jnp.float32)
        info["ref_qd"] = ref["qd_ref"].astype(jnp.float32)
        info["ref_contact"] = ref["in_contact"].astype(jnp.float32)
        info["tracked"] = jnp.asarray(tracked, jnp.float32)
        info["ref_height"] = self._height_target(info["command"])
        info["next_phase"] = jnp.asarray(ref["next_phase"], jnp.float32)
        info["measured"] = jnp.concatenate([v_H, jnp.array([height]), contact, jnp.array([pitch, roll])])
        info["arm_des_rel"] = arm_des_rel
        # An ended episode restarts in the default pose (Brax auto-reset keeps info): so do the teleop targets.
        info["tp_tgt"] = jnp.where(done, jnp.asarray(self.arm_default), info["tp_tgt"])
        info["tp_vel"] = jnp.where(done, 0.0, info["tp_vel"])
        info["tp_w"] = jnp.where(done, 0.0, info["tp_w"])
        info["hf"] = jnp.where(done, 0.0, info["hf"])
        info["hf_tgt"] = jnp.where(done, 0.0, info["hf_tgt"])
        if ident:  # the restarted episode's motors have no command history
            info["act_line"] = dict(info["act_line"], count=jnp.where(done, 0, info["act_line"]["count"]))
        obs = self._obs(data, info, k_noise)
        metrics = dict(state.metrics)  # wrappers add their own entries (e.g. "reward")
        metrics.update({"lin_vel_err": jnp.sqrt(lin_err), "yaw_rate_err": jnp.sqrt(yaw_err),
                   "pitch_err": jnp.abs(cmd[3] - pitch), "roll_err": jnp.abs(cmd[4] - roll),
                   "height_err": jnp.sqrt(h_err), "ref_q_err": jnp.sqrt(ref_q_err / LEG),
                   "contact_match": contact_match, "energy": energy, "foot_slip": foot_slip})
        metrics.update({f"reward_{t}": jnp.asarray(terms.get(t, 0.0), jnp.float32) for t in REWARD_TERMS})
        data = jax.tree_util.tree_map(lambda new, old: jnp.where(jnp.all(jnp.isfinite(data.qpos)), new, old),
                                      data, state.pipeline_state)
        return state.replace(pipeline_state=data, obs=obs, reward=reward, done=done.astype(jnp.float32),
                             metrics=metrics, info=info)

    # ---- helpers ---------------------------------------------------------------------------
    def _push_interval(self, rng):
        """Control steps until the next push (EnvConfig.push_interval, uniform)."""
        lo, hi = self.cfg.push_interval
        return jnp.round(jax.random.uniform(rng, (), minval=lo, maxval=hi) / self.cfg.control_dt).astype(jnp.int32)

    def _push(self, data, timer, rng):
        """Counts the push timer down; at zero adds a horizontal velocity change to the floating
        base (world frame, EnvConfig.push_vel) and draws the next interval. Returns (data, timer)."""
        k = jax.random.split(rng, 3)
        timer = timer - 1
        due = timer <= 0
        angle = jax.random.uniform(k[0], (), minval=0.0, maxval=2 * math.pi)
        speed = jax.random.uniform(k[1], (), minval=self.cfg.push_vel[0], maxval=self.cfg.push_vel[1])
        kick = jnp.where(due, speed, 0.0) * jnp.array([jnp.cos(angle), jnp.sin(angle)])
        data = data.replace(qvel=data.qvel.at[0:2].add(kick))
        timer = jnp.where(due, self._push_interval(k[2]), timer)
        return data, timer

    def _foot_contacts(self, data):
        con = data._impl.contact if hasattr(data, "_impl") and hasattr(data._impl, "contact") else data.contact
        dist = con.dist
        g1, g2 = con.geom1, con.geom2
        on_floor = (g1 == self.floor_geom) | (g2 == self.floor_geom)  # not a foot on the other foot
        out = []
        for geoms in self.foot_geoms:
            hit = jnp.zeros(dist.shape, bool)
            for g in geoms:
                hit = hit | (g1 == g) | (g2 == g)
            out.append(jnp.any(hit & on_floor & (dist < 2e-3)))
        return jnp.stack(out).astype(jnp.float32)

    def raw_obs(self, data, info):
        """Actor observation terms before scaling (SI units), contract order."""
        R = _quat_to_rot(data.qpos[3:7])
        grav_B = R.T @ jnp.array([0.0, 0.0, -1.0])
        gyro_B = data.qvel[3:6]
        q_rel = data.qpos[7:7 + LEG] - jnp.asarray(self.q_default[:LEG])
        qd = data.qvel[6:6 + LEG]
        ref_rel = info["ref_q"][:LEG] - jnp.asarray(self.q_default[:LEG])
        ph = 2 * math.pi * info["phase"]
        return [gyro_B, grav_B, info["tracked"], q_rel, qd, info["last_action"], ref_rel,
                jnp.array([jnp.sin(ph), jnp.cos(ph)])]

    def _obs(self, data, info, rng):
        terms = self.raw_obs(data, info)
        clean = jnp.concatenate(terms)
        n = self.cfg.noise
        k = jax.random.split(rng, 4)
        noisy = [terms[0] + n["gyro"] * jax.random.normal(k[0], (3,)),
                 terms[1] + n["gravity"] * jax.random.normal(k[1], (3,)), terms[2],
                 terms[3] + n["q"] * jax.random.normal(k[2], (LEG,)),
                 terms[4] + n["qd"] * jax.random.normal(k[3], (LEG,)), terms[5], terms[6], terms[7]]
        scale = jnp.asarray(self.obs_scale)
        actor = jnp.clip(jnp.concatenate(noisy) * scale, -OBS_CLIP, OBS_CLIP)
        measured = info["measured"]
        hands = jnp.asarray(self.hand_bodies)
        hand_mass = self.sys.body_mass[hands] - jnp.asarray(self.mj_model.body_mass[self.hand_bodies])
        priv = jnp.concatenate([jnp.clip(clean * scale, -OBS_CLIP, OBS_CLIP), measured, info["ref_contact"],
                                jnp.array([info["kp_scale"], info["delay"]]), info["arm_des_rel"], hand_mass])
        return {"state": actor, "privileged_state": priv}


def make_randomization_fn(env: G1PmgEnv):
    c = env.cfg
    mj = env.mj_model

    def randomize(sys, rng):
        @jax.vmap
        def one(key):
            k = jax.random.split(key, 8)
            friction = sys.geom_friction.at[:, 0].set(jax.random.uniform(k[0], (), minval=c.friction[0],
                                                                         maxval=c.friction[1]))
            mass = sys.body_mass * jax.random.uniform(k[1], (mj.nbody,), minval=c.mass_scale[0], maxval=c.mass_scale[1])
            mass = mass.at[env.torso_body].add(jax.random.uniform(k[2], (), minval=c.payload[0], maxval=c.payload[1]))
            hand = jax.random.uniform(k[6], (2,), minval=c.hand_payload[0], maxval=c.hand_payload[1])
            hand = jnp.where(jax.random.uniform(k[7], (2,)) < c.p_payload, hand, 0.0)
            mass = mass.at[jnp.asarray(env.hand_bodies)].add(hand)
            if c.gains == "physically_informed":  # the generic range relative to the nominal 0.01, around I
                arm = sys.dof_armature.at[6:].set(jnp.asarray(env.armature) * jax.random.uniform(
                    k[3], (29,), minval=c.armature[0] / NOMINAL_ARMATURE, maxval=c.armature[1] / NOMINAL_ARMATURE))
            else:
                arm = sys.dof_armature.at[6:].set(jax.random.uniform(k[3], (29,), minval=c.armature[0],
                                                                     maxval=c.armature[1]))
            fl = sys.dof_frictionloss.at[6:].set(jax.random.uniform(k[4], (29,), minval=c.frictionloss[0],
                                                                    maxval=c.frictionloss[1]))
            # The PD's kd, scaled, where it is implicit; with pd_damping "explicit" the step computes it, and the
            # joints keep their own 0.05 (no kd draw).
            damp = (sys.dof_damping.at[6:].set(0.05 + jnp.asarray(env.kd) * jax.random.uniform(
                k[5], (), minval=c.kd_scale[0], maxval=c.kd_scale[1])) if c.pd_damping == "implicit" else sys.dof_damping)
            return friction, mass, arm, fl, damp

        friction, mass, arm, fl, damp = one(rng)
        fields = {"geom_friction": friction, "body_mass": mass, "dof_armature": arm, "dof_frictionloss": fl,
                  "dof_damping": damp}
        in_axes = jax.tree_util.tree_map(lambda x: None, sys)
        in_axes = in_axes.replace(**{k: 0 for k in fields})
        return sys.replace(**fields), in_axes

    return randomize
