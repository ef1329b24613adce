#!/usr/bin/env python3
"""pmg-train's command line refuses bad reward settings with the flag named (argparse exit 2):
--reward-weight NAME=W parses into a dict, a missing '=' or a non-finite W is refused, and so are
a non-positive --tracking-sigma and a negative --yaw-rate-weight; --command-range AXIS=LO,HI parses
into a dict, and an unknown axis, LO >= HI, a missing HI or a height below 0.3 m are refused;
--command-slew is off unless given; --command-envelopes needs it, and reads a controller config's `commands:`
values, refusing a file with the block missing or a key missing, zero or not finite; --joint-stop-timeconst parses and one below 2 physics steps (0.01 s) or
non-finite is refused; --p-stop, --stop-keeps-posture, --p-posture-walk and --p-reset-reference (unset by
default) parse and a value outside
[0, 1] is refused; --push-vel LO,HI parses and a reversed, negative, non-finite or one-value range is refused;
and --p-combined parses and a value outside [0, 0.6] is refused; --command-focus AXIS=LO,HI (LO <= HI) with --p-focus
parses (off by default), and one without the other, p_focus 0 or outside [0, 1], an unknown axis, a reversed or
non-finite bound or a height below 0.3 m is refused (the box inside the ranges: the smoke run's env); --action-offset (default | reference) and
--action-scale-factor parse, and an unknown offset or a factor outside (0, 2] is refused; --action-scale-joint-factor
JOINT=F (repeatable) multiplies that joint of both legs after the uniform factor, and an unknown joint, a missing F or
one outside (0, 2] is refused;
--discounting (default 0.97), --reward-scaling (default 1.0) and --mirror-loss (default 0) parse, and a
discount outside (0, 1), a non-positive or non-finite scale or a negative or non-finite mirror weight is refused;
--warmup-steps (default 0: no warm-up config) parses, its config changes the three tracking widths and
nothing else, and a negative count, one not below --timesteps, a warm-up width without --warmup-steps or a
non-positive or non-finite width is refused; bench_env_step.py's --parts parses in order and an
unknown part, an empty list or a count below 1 is refused; --clips parses, and --action-scale-from returns an earlier run's scale and refuses a bad file naming it. (An unknown NAME is refused in
main(), against EnvConfig.w, which needs JAX: the smoke run's environment.)"""
import contextlib
import io
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import train_pmg  # noqa: E402

failures = []
n_cases = 0  # refusal cases run (both loops below)
args = train_pmg.parse_args(["--out", "/tmp/x", "--reward-weight", "orientation=1.0", "--reward-weight", "height=2"])
if args.reward_weight != {"orientation": 1.0, "height": 2.0}:
    failures.append(f"--reward-weight parsed as {args.reward_weight}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--command-range", "vx=-0.65,1.0", "--command-range", "wz=-1,1"])
if args.command_range != {"vx": (-0.65, 1.0), "wz": (-1.0, 1.0)}:
    failures.append(f"--command-range parsed as {args.command_range}")
if args.command_slew or not train_pmg.parse_args(["--out", "/tmp/x", "--command-slew"]).command_slew:
    failures.append("--command-slew: off by default, on with the flag")
if train_pmg.parse_args(["--out", "/tmp/x", "--p-stop", "0.5"]).p_stop != 0.5:
    failures.append("--p-stop 0.5 not parsed")
if train_pmg.parse_args(["--out", "/tmp/x", "--p-reset-reference", "0.3"]).p_reset_reference != 0.3:
    failures.append("--p-reset-reference 0.3 not parsed")
if train_pmg.parse_args(["--out", "/tmp/x"]).p_reset_reference is not None:
    failures.append("--p-reset-reference: unset by default (EnvConfig.p_reset_reference 0 stays)")
if train_pmg.parse_args(["--out", "/tmp/x", "--stop-keeps-posture", "0.6"]).stop_keeps_posture != 0.6:
    failures.append("--stop-keeps-posture 0.6 not parsed")
if train_pmg.parse_args(["--out", "/tmp/x", "--push-vel", "0.1,0.6"]).push_vel != (0.1, 0.6):
    failures.append("--push-vel 0.1,0.6 not parsed")
if train_pmg.parse_args(["--out", "/tmp/x", "--p-posture-walk", "0.7"]).p_posture_walk != 0.7:
    failures.append("--p-posture-walk 0.7 not parsed")
if train_pmg.parse_args(["--out", "/tmp/x", "--p-combined", "0.5"]).p_combined != 0.5:
    failures.append("--p-combined 0.5 not parsed")
args = train_pmg.parse_args(["--out", "/tmp/x", "--action-offset", "reference", "--action-scale-factor", "0.5"])
if (args.action_offset, args.action_scale_factor) != ("reference", 0.5):
    failures.append(f"--action-offset reference --action-scale-factor 0.5 parsed as {args.action_offset}, "
                    f"{args.action_scale_factor}")
args = train_pmg.parse_args(["--out", "/tmp/x"])
if (args.action_offset, args.action_scale_factor) != ("default", 1.0):
    failures.append(f"--action-offset / --action-scale-factor defaults: {args.action_offset}, {args.action_scale_factor}")
base = [0.4, 0.5, 1.0, 1.0, 0.6, 0.3] * 2  # a leg action scale, left then right
scale = train_pmg.leg_action_scale(base, args)
if not all(abs(a - b) < 1e-6 for a, b in zip(scale, base)):
    failures.append(f"leg_action_scale without factors changed the scale: {list(scale)}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--action-scale-factor", "0.5", "--action-scale-joint-factor",
                             "knee=1.2", "--action-scale-joint-factor", "hip_pitch=1.5"])
scale = train_pmg.leg_action_scale(base, args)
want = [b * 0.5 * {0: 1.5, 3: 1.2}.get(j % 6, 1.0) for j, b in enumerate(base)]
if not all(abs(a - b) < 1e-6 for a, b in zip(scale, want)):
    failures.append(f"--action-scale-factor 0.5 with knee=1.2, hip_pitch=1.5 gave {list(scale)}, expected {want}")
if train_pmg.parse_args(["--out", "/tmp/x", "--joint-stop-timeconst", "0.01"]).joint_stop_timeconst != 0.01:
    failures.append("--joint-stop-timeconst 0.01 not parsed")
if (args.discounting, args.reward_scaling, args.mirror_loss) != (0.97, 1.0, 0.0):
    failures.append(f"--discounting / --reward-scaling / --mirror-loss defaults: {args.discounting}, "
                    f"{args.reward_scaling}, {args.mirror_loss}")
if train_pmg.parse_args(["--out", "/tmp/x", "--mirror-loss", "0.5"]).mirror_loss != 0.5:
    failures.append("--mirror-loss 0.5 not parsed")
args = train_pmg.parse_args(["--out", "/tmp/x", "--discounting", "0.99", "--reward-scaling", "0.33"])
if (args.discounting, args.reward_scaling) != (0.99, 0.33):
    failures.append(f"--discounting 0.99 --reward-scaling 0.33 parsed as {args.discounting}, {args.reward_scaling}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--command-focus", "vx=-0.6,-0.3", "--command-focus", "height=0.7,0.7",
                             "--p-focus", "0.1"])
if (args.command_focus, args.p_focus) != ({"vx": (-0.6, -0.3), "height": (0.7, 0.7)}, 0.1):
    failures.append(f"--command-focus vx=-0.6,-0.3 height=0.7,0.7 --p-focus 0.1 parsed as {args.command_focus}, "
                    f"{args.p_focus}")
args = train_pmg.parse_args(["--out", "/tmp/x"])
if (args.command_focus, args.p_focus) != ({}, None):
    failures.append(f"--command-focus / --p-focus defaults: {args.command_focus}, {args.p_focus} (expected off)")
if train_pmg.parse_args(["--out", "/tmp/x", "--height-sigma", "0.001"]).height_sigma != 0.001:
    failures.append("--height-sigma 0.001 not parsed")
for bad, flag in ((["--p-stop", "1.5"], "--p-stop"),
                  (["--p-stop", "nan"], "--p-stop"),
                  (["--p-reset-reference", "1.5"], "--p-reset-reference"),
                  (["--p-reset-reference", "nan"], "--p-reset-reference"),
                  (["--p-reset-reference", "-0.1"], "--p-reset-reference"),
                  (["--stop-keeps-posture", "1.2"], "--stop-keeps-posture"),
                  (["--stop-keeps-posture", "nan"], "--stop-keeps-posture"),
                  (["--push-vel", "0.6,0.1"], "--push-vel"),
                  (["--push-vel", "0.4"], "--push-vel"),
                  (["--push-vel", "0,0.4,1"], "--push-vel"),
                  (["--push-vel", "-0.1,0.4"], "--push-vel"),
                  (["--push-vel", "0,nan"], "--push-vel"),
                  (["--p-posture-walk", "-0.1"], "--p-posture-walk"),
                  (["--p-posture-walk", "nan"], "--p-posture-walk"),
                  (["--p-combined", "0.7"], "--p-combined"),
                  (["--joint-stop-timeconst", "0.005"], "--joint-stop-timeconst"),
                  (["--joint-stop-timeconst", "nan"], "--joint-stop-timeconst"),
                  (["--p-combined", "nan"], "--p-combined"),
                  (["--command-range", "vx=1.0,-0.5"], "--command-range"),
                  (["--command-range", "speed=-1,1"], "--command-range"),
                  (["--command-range", "vy=-0.4"], "--command-range"),
                  (["--command-range", "height=0.1,0.78"], "--command-range"),
                  (["--command-focus", "vx=-0.6,-0.3"], "--p-focus"),
                  (["--p-focus", "0.1"], "--p-focus"),
                  (["--command-focus", "vx=-0.6,-0.3", "--p-focus", "0"], "--p-focus"),
                  (["--command-focus", "vx=-0.6,-0.3", "--p-focus", "1.5"], "--p-focus"),
                  (["--command-focus", "vx=-0.6,-0.3", "--p-focus", "nan"], "--p-focus"),
                  (["--command-focus", "vx=-0.3,-0.6", "--p-focus", "0.1"], "--command-focus"),
                  (["--command-focus", "speed=0,1", "--p-focus", "0.1"], "--command-focus"),
                  (["--command-focus", "height=0.2,0.7", "--p-focus", "0.1"], "--command-focus"),
                  (["--command-focus", "vy=inf,1", "--p-focus", "0.1"], "--command-focus"),
                  (["--reward-weight", "orientation"], "--reward-weight"),
                  (["--reward-weight", "orientation=nan"], "--reward-weight"),
                  (["--reward-weight", "height=abc"], "--reward-weight"),
                  (["--tracking-sigma", "0"], "--tracking-sigma"),
                  (["--orientation-sigma", "0"], "--orientation-sigma"),
                  (["--orientation-sigma", "nan"], "--orientation-sigma"),
                  (["--height-sigma", "0"], "--height-sigma"),
                  (["--height-sigma", "-0.001"], "--height-sigma"),
                  (["--yaw-rate-weight", "-1"], "--yaw-rate-weight"),
                  (["--action-offset", "ref"], "--action-offset"),
                  (["--action-scale-factor", "0"], "--action-scale-factor"),
                  (["--action-scale-factor", "nan"], "--action-scale-factor"),
                  (["--action-scale-factor", "3"], "--action-scale-factor"),
                  (["--action-scale-joint-factor", "shin=1.2"], "--action-scale-joint-factor"),
                  (["--action-scale-joint-factor", "knee"], "--action-scale-joint-factor"),
                  (["--action-scale-joint-factor", "knee=0"], "--action-scale-joint-factor"),
                  (["--action-scale-joint-factor", "knee=2.5"], "--action-scale-joint-factor"),
                  (["--action-scale-joint-factor", "knee=nan"], "--action-scale-joint-factor"),
                  (["--discounting", "1"], "--discounting"),
                  (["--discounting", "0"], "--discounting"),
                  (["--discounting", "nan"], "--discounting"),
                  (["--reward-scaling", "0"], "--reward-scaling"),
                  (["--reward-scaling", "nan"], "--reward-scaling"),
                  (["--reward-scaling", "inf"], "--reward-scaling"),
                  (["--mirror-loss", "-1"], "--mirror-loss"),
                  (["--mirror-loss", "nan"], "--mirror-loss"),
                  (["--mirror-loss", "inf"], "--mirror-loss"),
                  (["--warmup-steps", "-1"], "--warmup-steps"),
                  (["--timesteps", "1000", "--warmup-steps", "1000"], "--warmup-steps"),
                  (["--warmup-tracking-sigma", "0.3"], "--warmup-tracking-sigma"),
                  (["--warmup-height-sigma", "0.03"], "--warmup-height-sigma"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-tracking-sigma", "0"],
                   "--warmup-tracking-sigma"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-height-sigma", "nan"],
                   "--warmup-height-sigma"),
                  (["--warmup-p-posture-walk", "0"], "--warmup-p-posture-walk"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-p-posture-walk", "1.5"],
                   "--warmup-p-posture-walk"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-p-posture-walk", "nan"],
                   "--warmup-p-posture-walk"),
                  (["--warmup-orientation-sigma", "0.05"], "--warmup-orientation-sigma"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-orientation-sigma", "0"],
                   "--warmup-orientation-sigma"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-orientation-sigma", "inf"],
                   "--warmup-orientation-sigma"),
                  (["--warmup-evals", "4"], "--warmup-evals"),
                  (["--action-noise-scale", "0"], "--action-noise-scale"),
                  (["--action-noise-scale", "-0.5"], "--action-noise-scale"),
                  (["--action-noise-scale", "inf"], "--action-noise-scale"),
                  (["--timesteps", "1000", "--warmup-steps", "400", "--warmup-evals", "0"], "--warmup-evals"),
                  (["--command-envelopes", "config/controller/g1_sil_policy_wh6g.yaml"], "--command-envelopes")):
    n_cases += 1
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            train_pmg.parse_args(["--out", "/tmp/x"] + bad)
        failures.append(f"{bad} accepted")
    except SystemExit as e:
        if e.code != 2 or flag not in err.getvalue().splitlines()[-1]:
            failures.append(f"{bad}: exit {e.code}, message {err.getvalue().splitlines()[-1]!r}")
# --command-envelopes: the controller config's `commands:` values become EnvConfig fields; a file without the
# block, or with a key missing, zero (an envelope off; only the crouched one may be) or not finite, is refused naming the
# file and the key.
import tempfile  # noqa: E402

if train_pmg.parse_args(["--out", "/tmp/x", "--command-slew", "--command-envelopes", "c.yaml"]).command_envelopes != "c.yaml":
    failures.append("--command-envelopes c.yaml not parsed")
env_fields = train_pmg.command_envelopes_from("config/controller/g1_sil_policy_wh6g.yaml")
want = {"command_envelopes": True, "envelope_max_velocity": (1.0, 0.4, 0.8), "crouched_height": 0.62,
        "crouched_max_velocity": (0.3, 0.3, 0.6), "walking_min_height": 0.66, "walking_min_height_hold_s": 1.5,
        "bent_pitch": 0.4, "bent_max_velocity": (0.8, 0.4, 0.8), "command_height_rate": 0.2}
if any(env_fields.get(k) != v for k, v in want.items()):
    failures.append(f"--command-envelopes config/controller/g1_sil_policy_wh6g.yaml read as {env_fields}")
with open("config/controller/g1_sil_policy_wh6g.yaml") as f:
    shipped = f.read()
with tempfile.TemporaryDirectory() as tmp:
    for text, key in ((shipped.replace("walking_min_height: 0.66", "walking_min_height: 0.0"), "walking_min_height"),
                      (shipped.replace("crouched_max_velocity: [0.3, 0.3, 0.6]", "crouched_max_velocity: [0.3, 0.3]"),
                       "crouched_max_velocity"),
                      (shipped.replace("bent_pitch: 0.4", "bent_pitch: .nan"), "bent_pitch"),
                      (shipped.replace("bent_pitch: 0.4", "bent_pitch: 0"), "bent_pitch"),
                      (shipped.replace("crouched_height: 0.62", "crouched_height: -0.1"), "crouched_height"),
                      (shipped.replace("crouched_height: 0.62", "crouched_per_axis: true\n  crouched_height: 0.62"),
                       "crouched_per_axis"),
                      (shipped.replace("\ncommands:", "\nkommands:"), "commands")):
        n_cases += 1
        path = os.path.join(tmp, "bad.yaml")
        with open(path, "w") as f:
            f.write(text)
        try:
            train_pmg.command_envelopes_from(path)
            failures.append(f"--command-envelopes with a bad {key} accepted")
        except SystemExit as e:
            if path not in str(e) or key not in str(e):
                failures.append(f"--command-envelopes with a bad {key}: message {e}")
# crouched_height 0: the crouched envelope off (the controller's meaning), everything else as read.
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "off.yaml")
    with open(path, "w") as f:
        f.write(shipped.replace("crouched_height: 0.62", "crouched_height: 0"))
    off = train_pmg.command_envelopes_from(path)
    if off.get("crouched_height") != 0.0 or {k: v for k, v in off.items() if k != "crouched_height"} != \
            {k: v for k, v in env_fields.items() if k != "crouched_height"}:
        failures.append(f"--command-envelopes with crouched_height 0 read as {off}")
# --warmup-steps: off by default (no warm-up config); on, its config changes the three widths and nothing else.
import dataclasses  # noqa: E402


@dataclasses.dataclass(frozen=True)
class _Cfg:  # EnvConfig's width fields and p_posture_walk (the smoke run's PPO part uses the real one)
    lin_vel_sigma: float = 0.05
    yaw_rate_sigma: float = 0.05
    height_sigma: float = 0.0005
    orientation_sigma: float = 0.05
    episode_length: int = 1000
    p_posture_walk: float = 0.6


args = train_pmg.parse_args(["--out", "/tmp/x"])
if args.warmup_steps != 0 or train_pmg.warmup_config(_Cfg(), args) is not None:
    failures.append(f"--warmup-steps default: {args.warmup_steps}, warm-up config {train_pmg.warmup_config(_Cfg(), args)}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--timesteps", "1000", "--warmup-steps", "400"])
if train_pmg.warmup_config(_Cfg(), args) != _Cfg(0.25, 0.25, 0.02, 0.05, 1000):
    failures.append(f"--warmup-steps 400, default widths: warm-up config {train_pmg.warmup_config(_Cfg(), args)}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--timesteps", "1000", "--warmup-steps", "400",
                             "--warmup-tracking-sigma", "0.3", "--warmup-height-sigma", "0.01"])
if (args.warmup_steps, train_pmg.warmup_config(_Cfg(), args)) != (400, _Cfg(0.3, 0.3, 0.01, 0.05, 1000)):
    failures.append(f"--warmup-steps 400 with widths 0.3, 0.01: {args.warmup_steps}, "
                    f"{train_pmg.warmup_config(_Cfg(), args)}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--timesteps", "1000", "--warmup-steps", "400",
                             "--warmup-p-posture-walk", "0"])
if train_pmg.warmup_config(_Cfg(), args) != _Cfg(0.25, 0.25, 0.02, 0.05, 1000, 0.0):
    failures.append(f"--warmup-p-posture-walk 0: warm-up config {train_pmg.warmup_config(_Cfg(), args)}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--timesteps", "1000", "--warmup-steps", "400",
                             "--orientation-sigma", "0.01", "--warmup-orientation-sigma", "0.05"])
if train_pmg.warmup_config(_Cfg(orientation_sigma=0.01), args) != _Cfg(0.25, 0.25, 0.02, 0.05, 1000):
    failures.append(f"--warmup-orientation-sigma 0.05: warm-up config {train_pmg.warmup_config(_Cfg(orientation_sigma=0.01), args)}")
args = train_pmg.parse_args(["--out", "/tmp/x", "--timesteps", "1000", "--warmup-steps", "400", "--orientation-sigma", "0.01"])
if train_pmg.warmup_config(_Cfg(orientation_sigma=0.01), args).orientation_sigma != 0.01:
    failures.append("without --warmup-orientation-sigma the warm-up keeps the run's orientation width")
args = train_pmg.parse_args(["--out", "/tmp/x", "--timesteps", "1000", "--warmup-steps", "400", "--warmup-evals", "5",
                             "--keep-actors"])
if (args.warmup_evals, args.keep_actors) != (5, True):
    failures.append(f"--warmup-evals 5 --keep-actors parsed as {(args.warmup_evals, args.keep_actors)}")
args = train_pmg.parse_args(["--out", "/tmp/x"])
if (args.warmup_evals, args.keep_actors, args.action_noise_scale) != (1, False, 1.0):
    failures.append(f"defaults: warmup_evals {args.warmup_evals}, keep_actors {args.keep_actors} (want 1, False)")
if train_pmg.parse_args(["--out", "/tmp/x", "--clips", "config/clips/other"]).clips != "config/clips/other":
    failures.append("--clips not parsed")
# --action-scale-from: the scale of an earlier run's train_config.json; a bad file is refused naming the flag.
import json  # noqa: E402
import tempfile  # noqa: E402
with tempfile.TemporaryDirectory() as tmp:
    good = os.path.join(tmp, "good.json")
    with open(good, "w") as f:
        json.dump({"action_scale": [0.5] * 6 + [0.25] * 6}, f)
    if list(train_pmg.action_scale_from(good)) != [0.5] * 6 + [0.25] * 6:
        failures.append("--action-scale-from: the scale of a valid train_config.json not returned")
    for name, doc in (("short", {"action_scale": [0.5] * 11}), ("zero", {"action_scale": [0.0] * 12}),
                      ("missing", {"argv": []}), ("text", "not json")):
        bad = os.path.join(tmp, name + ".json")
        with open(bad, "w") as f:
            f.write(doc if isinstance(doc, str) else json.dumps(doc))
        try:
            train_pmg.action_scale_from(bad)
            failures.append(f"--action-scale-from {name}: accepted")
        except SystemExit as e:
            if "--action-scale-from" not in str(e.code) or bad not in str(e.code):
                failures.append(f"--action-scale-from {name}: message {e.code!r}")
# The benches (import JAX only in main()): parts parse in order; an unknown part, an empty list or a count < 1
# is refused, and the message names the flag.
import bench_compile  # noqa: E402
import bench_env_step  # noqa: E402
BENCH_CASES = (
    (bench_env_step, ["--parts", "pmg_gco, physics", "--num-envs", "8"], ["pmg_gco", "physics"],
     ((["--parts", "physics,gco"], "--parts"), (["--parts", ","], "--parts"), (["--steps", "0"], "--steps"),
      (["--num-envs", "-1"], "--num-envs"))),
    (bench_compile, ["--parts", "step, generator"], ["step", "generator"],
     ((["--parts", "generator,gco"], "--parts"), (["--parts", ","], "--parts"))),
)
for module, good, parts, refusals in BENCH_CASES:
    name = module.__name__
    if module.parse_args(good).parts != parts:
        failures.append(f"{name} {good} not parsed in order")
    for bad, flag in refusals:
        n_cases += 1
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                module.parse_args(bad)
            failures.append(f"{name} {bad} accepted")
        except SystemExit as e:
            if e.code != 2 or flag not in err.getvalue().splitlines()[-1]:
                failures.append(f"{name} {bad}: exit {e.code}, message {err.getvalue().splitlines()[-1]!r}")
print("\n".join("FAIL: " + f for f in failures) if failures else f"pmg-train, bench_env_step and bench_compile arguments: {n_cases} refusals as expected, "
      f"and the parsed values")
sys.exit(1 if failures else 0)
