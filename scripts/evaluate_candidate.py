#!/usr/bin/env python3
"""Evaluate a trained actor against issue 12's targets through the product path, in one command.

  python3 scripts/evaluate_candidate.py --model RUN/g1_pmg_policy.onnx --out RUN/eval \\
      [--base-config config/controller/g1_sil_policy_v20b.yaml] [--bin build/bin] [--jobs 2] [--quick]
      [--mjx-actor RUN/actor.npz] [--sliding-friction MU]
  python3 scripts/evaluate_candidate.py --report-only --out RUN/eval      # the report from what is there

What a person otherwise types by hand for each candidate (training/results/fidelity/seeds_V20b/README.md):
1. (with --mjx-actor) the actor alone in its own training simulator: training/eval_mjx.py on the
   crouched backward walks (training/results/fidelity/seeds_V20b/crouched_backward.yaml), whose gait
   table shows a run (both feet off the floor) before any SIL time is spent. Needs .venv-training
   and the run's train_config.json beside the actor. Written to mjx_crouched_backward.{npz,txt}.
1b. (with --mjx-floor-stops N) N randomized robots of its training distribution in MJX on the 0.62 m
   sweep's side-step and turn stops (training/results/fidelity/crouched/floor_stops_0.62.yaml, --seed 1):
   robots fallen, which ranks actors as step 4b does. Written to mjx_floor_stops.{npz,txt}.
   It is a screen: when more than --screen-max-fallen of the robots fall (default 10 %), steps 2-4b are
   not run, and screen.json and report.md say so.
2. The command-response feed-forward fitted for this actor: pmg_policy_sil on the calibration sweeps
   config/policies/response_sweep_{1,2,3}.yaml (upright) and _{7,8}.yaml (crouched, 0.66-0.78 m) with
   the base config, this model and the feed-forward off (feedforward/calibration_*/), then
   scripts/fit_command_response.py, the crouch measured from the standing height the runs record
   (feedforward/fit.yaml, .txt, .png). Evaluation scripts are never used for the fit.
3. controller.yaml: the base config with this model and the fitted feed-forward; its relative paths
   (robot, clips, gco, policy.model) rewritten for the output folder, everything else unchanged.
4. The battery, through pmg_policy_sil --controller controller.yaml, --jobs runs at a time: the
   envelope grid and its mirror image (seeds 0-11), Table I (seeds 0-9, no restart), the posture walks
   (seeds 120-131), the crouched probe (seeds 36-47) and the crouched backward walks (seeds 0-1).
   --quick runs one seed of each and one sweep (a smoke of the pipeline, not a verdict).
4b. The crouched stress sweep, where the battery is blind: training/results/fidelity/crouched/
   crouched_sweep_0.62.yaml (87 s of walks and stops crouched to 0.62 m) on seeds 0-71, 6 runs of 12 seeds
   (stress_0.62/), 6.5 min with --jobs 2; --skip-stress leaves it out.
   --sliding-friction MU runs steps 4 and 4b on a floor of sliding friction MU (pmg_policy_sil
   --sliding-friction; [0.1, 2]; the MJCF's is 1.0) and leaves the feed-forward's calibration runs (step 2)
   on the MJCF's floor: the actor's fit is the shipped one, the floor is what changes. A run whose summary is
   already there on another floor is refused, not reused.
5. report.md: per battery the velocity segments in band (±15 % or 0.05 m/s / 0.08 rad/s) of the
   command and of the shaper's command (how many the shaper's envelopes slowed), posture misses (pitch/roll 0.03 rad, height 0.015 m), cross-coupling beyond 0.05 rad, runaways and falls
   (scripts/segment_band.py's score), Table I's mean errors, the stress sweep's runs with a fall and the
   segments they fell in, the MJX floor stops' fallen robots, and the MJX gait: what issue 12 asks. It names
   the floor friction the SIL runs recorded (summary.json's floor_friction), and the reference the robot was told to
   stand in (scripts/standing_reference.py: the largest hip yaw and knee difference at the end of a standing
   segment, kept in each battery's standing_reference.json).
Each step writes its command line into its folder (command.txt) and skips work whose summary (or
feedforward/fit.yaml) already exists, so an interrupted evaluation resumes; delete fit.yaml to refit. Units: m/s, rad/s, rad, m.
"""
import argparse
import contextlib
import glob
import io
import json
import os
import re
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
# The battery's processes share MuJoCo's compiled model (loadMujocoModel's opt-in cache, docs/robot_model.md):
# about 0.3-0.6 s saved per seed. A PMG_MJCF_CACHE_DIR already set wins.
ENV = dict(os.environ)
ENV.setdefault("PMG_MJCF_CACHE_DIR", os.path.join(REPO, "build", "mjcf_cache"))
sys.path.insert(0, HERE)
import segment_band  # noqa: E402
import standing_reference  # noqa: E402

CROUCHED_BACKWARD = "training/results/fidelity/seeds_V20b/crouched_backward.yaml"
# The 0.62 m sweep's side-step and turn stops as the product path commands them, for randomized robots in MJX
# (--mjx-floor-stops N): it ranks actors as the SIL's stress sweep does (training/README.md "Stops that keep the
# crouch, from scratch" and "The height reward doubled, from scratch": wh6g 0, N24b 9, N24h 34, N24g 37 of 128).
FLOOR_STOPS = "training/results/fidelity/crouched/floor_stops_0.62.yaml"
# The screen's default: the share of those robots that may fall before the SIL steps are skipped. The one actor from
# scratch below it, N24b (9 of 128, 7 %), falls in 3-5 of 72 runs of the stress sweep; the two above it, N24h (34 of
# 128) and N24g (37), in 21 and 29 (training/README.md "The height reward doubled, from scratch").
SCREEN_MAX_FALLEN = 0.10
# name -> (command script, first seed, seeds, restart after a fall)
BATTERY = {
    "grid": ("config/policies/eval_envelope.yaml", 0, 12, True),
    "mirror": ("config/policies/eval_envelope_mirrored.yaml", 0, 12, True),
    "table1": ("config/policies/eval_commands.yaml", 0, 10, False),
    "posture_walks": ("training/results/fidelity/crouched/posture_walks.yaml", 120, 12, True),
    "probe_heights": ("training/results/fidelity/crouched/probe_heights.yaml", 36, 12, True),
    "crouched_backward": (CROUCHED_BACKWARD, 0, 2, True),
}
# The crouched stress sweep (step 4b): 87 s of walks and stops at 0.62 m, where the battery is blind. N24b falls in
# no battery seed but in 5 of its 72 runs, N24g in 29 (training/README.md "Stops that keep the crouch, from scratch").
# (command script, first seed, seeds, seeds per pmg_policy_sil run)
STRESS = ("training/results/fidelity/crouched/crouched_sweep_0.62.yaml", 0, 72, 12)
STRESS_DIR = "stress_0.62"
# (sweep, first seed, seeds): the calibration runs of the feed-forward fit; 7 and 8 walk crouched (the
# gains per crouch: docs/controller.md "Gains per crouch")
SWEEPS = [(1, 0, 2), (1, 2, 2), (2, 0, 2), (3, 0, 2), (7, 0, 2), (8, 0, 2)]
PATH_KEYS = ("robot", "clips", "gco")  # top-level keys holding paths relative to the config file
FLIGHT_LIMIT = 0.15  # share of a crouched walk's window with neither foot down that marks a run
MJCF_FRICTION = 1.0  # the floor's sliding friction in config/robots/g1's MJCF (MuJoCo's default); summaries before
# pmg_policy_sil recorded floor_friction ran on it
FRICTION_RANGE = (0.1, 2.0)  # what pmg_policy_sil --sliding-friction accepts (MujocoBackendOptions::sliding_friction)


def run(cmd, folder, log_name="log.txt", ok=(0,)):
    """Run @p cmd (argv) with its command line in folder/command.txt and its output in folder/log_name;
    an exit status outside @p ok raises RuntimeError naming the log. Returns the exit status."""
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "command.txt"), "w") as f:
        f.write(" ".join(shlex.quote(c) for c in cmd) + "\n")
    with open(os.path.join(folder, log_name), "w") as log:
        rc = subprocess.run(cmd, cwd=REPO, stdout=log, stderr=subprocess.STDOUT, env=ENV).returncode
    if rc not in ok:
        raise RuntimeError(f"{' '.join(cmd[:2])} ... exited {rc}; see {os.path.join(folder, log_name)}")
    return rc


def sil(args, folder, commands, first_seed, seeds, restart, extra, friction=None):
    """pmg_policy_sil into @p folder unless folder/summary.json exists; returns its path. @p friction: the floor's
    sliding friction (None: the MJCF's); a summary already there from another floor raises RuntimeError."""
    summary = os.path.join(folder, "summary.json")
    if friction is not None:
        extra = [*extra, "--sliding-friction", repr(friction)]
    if os.path.exists(summary):
        with open(summary) as f:
            had = json.load(f).get("floor_friction", MJCF_FRICTION)
        want = MJCF_FRICTION if friction is None else friction
        if abs(had - want) > 1e-9:
            raise RuntimeError(f"{summary}: ran on a floor of sliding friction {had}, not the {want} asked for; "
                               f"delete that folder to run it again")
    else:
        cmd = [os.path.join(args.bin, "pmg_policy_sil"), *extra, "--commands", commands, "--seeds", str(seeds),
               "--first-seed", str(first_seed), "--out", folder] + (["--restart-after-fall"] if restart else [])
        # Exit status 3: a run fell. That is a result (the report counts the falls), not a failed tool.
        if run(cmd, folder, ok=(0, 3)) == 3 and not os.path.exists(summary):
            raise RuntimeError(f"pmg_policy_sil exited 3 without {summary}; see {os.path.join(folder, 'log.txt')}")
    return summary


def rewrite_config(base_path, out_path, model_path, fit_path):
    """controller.yaml (step 3): @p base_path's text with policy.model = @p model_path, the
    velocity_feedback.feedforward lines of @p fit_path's keys (enabled, vx, vy, wz, max_correction; each
    must be one line in the base; @p fit_path None keeps the base's feed-forward), and the relative paths
    of PATH_KEYS and policy.model rewritten relative to @p out_path's folder. Comments and every other
    line stay. Raises ValueError naming the key when the base lacks one of them."""
    import yaml
    with open(base_path) as f:
        lines = f.read().split("\n")
    fit = {}
    if fit_path is not None:
        with open(fit_path) as f:
            fit = yaml.safe_load(f)["feedforward"]
    base_dir, out_dir = os.path.dirname(os.path.abspath(base_path)), os.path.dirname(os.path.abspath(out_path))

    def moved(value):
        return os.path.relpath(os.path.normpath(os.path.join(base_dir, value)), out_dir)
    done, section, sub = set(), None, None
    for i, line in enumerate(lines):
        m = re.match(r"^(\s*)([A-Za-z_]+):(\s*)([^#\s][^#]*?)?(\s*#.*)?$", line)
        if not m:
            continue
        indent, key, value, comment = len(m.group(1)), m.group(2), m.group(4), m.group(5) or ""
        if indent == 0:
            section, sub = key, None
            if key in PATH_KEYS and value:
                lines[i] = f"{key}: {moved(value)}{comment}"
                done.add(key)
        elif indent == 2 and section is not None:
            sub = key
            if section == "policy" and key == "model":
                lines[i] = f"  model: {os.path.relpath(os.path.abspath(model_path), out_dir)}{comment}"
                done.add("policy.model")
        elif indent == 4 and section == "velocity_feedback" and sub == "feedforward" and key in fit:
            t = fit[key]
            value = ("{" + ", ".join(f"{k}: {json.dumps(v)}" for k, v in t.items()) + "}" if isinstance(t, dict)
                     else json.dumps(t))
            lines[i] = f"    {key}: {value}"
            done.add(f"feedforward.{key}")
    want = set(PATH_KEYS) | {"policy.model"}
    if fit_path is not None:
        want |= {"feedforward.vx", "feedforward.vy", "feedforward.wz"}
    if want - done:
        raise ValueError(f"{base_path}: no {', '.join(sorted(want - done))} to rewrite (expected a policy "
                         f"controller config such as config/controller/g1_sil_policy_v20b.yaml)")
    text = "\n".join(lines)
    if fit_path is not None:
        header = (f"# Generated by scripts/evaluate_candidate.py from {os.path.relpath(base_path, REPO)}: its model and "
                  f"feed-forward replaced\n# (feed-forward fitted for this actor: feedforward/fit.yaml), paths relative "
                  f"to this file, everything else the base's.\n")
    else:
        header = (f"# Generated by scripts/evaluate_candidate.py --keep-feedforward from {os.path.relpath(base_path, REPO)}: "
                  f"its model replaced,\n# paths relative to this file, everything else (the feed-forward too) the base's.\n")
    with open(out_path, "w") as f:
        f.write(header + text)
    with open(out_path) as f:  # it must load, with the fit in it
        check = yaml.safe_load(f)
    got = check["velocity_feedback"]["feedforward"]
    for key in fit:
        if got.get(key) != fit[key]:
            raise ValueError(f"{out_path}: velocity_feedback.feedforward.{key} {got[key]} is not the fit's {fit[key]}")
    return out_path


def mjx_rollout(args, out, name, commands, extra=()):
    """eval_mjx.py (.venv-training) of --mjx-actor on @p commands with @p extra options into out/name.npz, its
    tables in out/name.txt, unless the .npz exists."""
    npz = os.path.join(out, f"{name}.npz")
    if not os.path.exists(npz):
        py = os.path.join(REPO, ".venv-training", "bin", "python")
        run([py, "training/eval_mjx.py", os.path.abspath(args.mjx_actor), "--commands", commands, *extra,
             "--out", npz], out, f"{name}.txt")


def mjx_gait(args, out):
    """Step 1: eval_mjx.py on the crouched backward walks; the gait table written to mjx_crouched_backward.txt."""
    mjx_rollout(args, out, "mjx_crouched_backward", CROUCHED_BACKWARD)


def mjx_floor_stops(args, out):
    """Step 1b: eval_mjx.py --randomized N --seed 1 on FLOOR_STOPS; its table written to mjx_floor_stops.txt."""
    mjx_rollout(args, out, "mjx_floor_stops", FLOOR_STOPS, ["--randomized", str(args.mjx_floor_stops), "--seed", "1"])


def floor_stops_count(out):
    """The MJX floor stops under @p out (mjx_floor_stops.npz): (robots fallen, robots, [(segment, fallen in it)] for
    the segments with a fall), or None when not run."""
    npz = os.path.join(out, "mjx_floor_stops.npz")
    if not os.path.exists(npz):
        return None
    import numpy as np
    z = np.load(npz)
    falls = [int(k) for k in z["segment_falls"]]
    return sum(falls), int(z["done"].shape[0]), [(str(n), k) for n, k in zip(z["segment_names"], falls) if k]


def screen(out, max_share):
    """The screen after step 1b: True when at most @p max_share (0-1) of the floor stops' robots fell. Writes
    out/screen.json (fallen, robots, max_share, passed), which the report reads."""
    fallen, robots, _ = floor_stops_count(out)
    passed = fallen <= max_share * robots
    with open(os.path.join(out, "screen.json"), "w") as f:
        json.dump({"fallen": fallen, "robots": robots, "max_share": max_share, "passed": passed}, f)
    return passed


def floor_stops_lines(out):
    """Report lines of the MJX floor stops: robots fallen of those rolled out, and per segment; the screen's
    verdict when it ran."""
    count = floor_stops_count(out)
    if count is None:
        return []
    fallen, robots, per = count
    lines = ["", f"MJX, the actor alone: randomized robots fallen on the floor stops ({FLOOR_STOPS}, --seed 1): "
                 f"**{fallen} of {robots}**" + (f" ({', '.join(f'{n} {k}' for n, k in per)})" if per else "")]
    path = os.path.join(out, "screen.json")
    if os.path.exists(path):
        with open(path) as f:
            v = json.load(f)
        share = f"{100 * v['fallen'] / v['robots']:.0f} % of the robots fell, {100 * v['max_share']:.0f} % allowed"
        lines.append(f"**Passed the MJX screen** ({share})." if v["passed"] else
                     f"**Rejected by the MJX screen** ({share} by --screen-max-fallen): steps 2-4b, the SIL, were not run.")
    return lines


def mjx_lines(out):
    """The MJX gait of the crouched walks (height below 0.76 m): name, v_x commanded and achieved, flight
    share, and whether the robot fell in the segment or before it."""
    npz = os.path.join(out, "mjx_crouched_backward.npz")
    if not os.path.exists(npz):
        return []
    import numpy as np
    z = np.load(npz)
    rows = []
    for k, name in enumerate(z["segment_names"]):
        cmd = z["segment_command"][k]
        if cmd[5] >= 0.76 or abs(cmd[0]) < 1e-9:
            continue
        ach, flight = float(z["segment_achieved"][k][0]), float(z["segment_gait"][k][0])
        # Fell in it, or fell before it (nothing left standing in its window: NaN means).
        fell = bool(z["segment_falls"][k]) or not (np.isfinite(ach) and np.isfinite(flight))
        rows.append((str(name), float(cmd[0]), ach, flight, fell))
    return rows


def stress_plan(quick=False):
    """The stress sweep's pmg_policy_sil runs: (folder under STRESS_DIR, first seed, seeds) each; one seed with
    @p quick."""
    _, first, seeds, per_run = STRESS
    if quick:
        seeds = per_run = 1
    return [(f"seeds{s}-{min(s + per_run, first + seeds) - 1}", s, min(per_run, first + seeds - s))
            for s in range(first, first + seeds, per_run)]


def stress_runs(out):
    """The stress sweep's runs under @p out (STRESS_DIR/seeds*/summary.json): a list of (seed, [(fall time [s],
    segment name)]) in seed order, the segment the one whose [t_begin, t_end) holds the fall; [] when not run."""
    runs = []
    for path in glob.glob(os.path.join(out, STRESS_DIR, "seeds*", "summary.json")):
        with open(path) as f:
            s = json.load(f)
        segs = [(g["t_begin"], g["t_end"], g["name"]) for g in s["segments"]]
        for r in s["runs"]:
            falls = [(t, next((n for b, e, n in segs if b <= t < e), "after the script")) for t in r["falls_s"]]
            runs.append((r["seed"], falls))
    return sorted(runs)


def stress_lines(out):
    """Report lines of the stress sweep: runs with a fall, and the falls counted by segment."""
    runs = stress_runs(out)
    if not runs:
        return []
    fallen = [seed for seed, falls in runs if falls]
    by_segment = {}
    for _, falls in runs:
        for _, name in falls:
            by_segment[name] = by_segment.get(name, 0) + 1
    lines = ["", f"Crouched stress sweep ({STRESS[0]}, seeds {runs[0][0]}-{runs[-1][0]}): runs with a fall "
                 f"**{len(fallen)} of {len(runs)}**" + (f" (seeds {', '.join(map(str, fallen))})" if fallen else "")]
    if by_segment:
        lines.append("falls by segment: " + ", ".join(f"{n} {k}" for n, k in
                                                      sorted(by_segment.items(), key=lambda kv: (-kv[1], kv[0]))))
    return lines


def floor_lines(out):
    """The report's line naming the floor friction that the SIL runs of steps 4-4b recorded (summary.json's
    floor_friction; a summary without it ran on the MJCF's floor): one value, or each value with its runs."""
    runs = {}
    paths = [os.path.join(out, name, "summary.json") for name in BATTERY]
    paths += sorted(glob.glob(os.path.join(out, STRESS_DIR, "*", "summary.json")))
    for path in filter(os.path.exists, paths):
        with open(path) as f:
            mu = float(json.load(f).get("floor_friction", MJCF_FRICTION))
        runs.setdefault(mu, []).append(os.path.relpath(os.path.dirname(path), out))
    if not runs:
        return []
    if len(runs) == 1:
        mu = next(iter(runs))
        return ["", f"Floor: sliding friction **{mu:g}** in every SIL run of the battery and the stress sweep"
                    + (" (the MJCF's)." if mu == MJCF_FRICTION else " (`--sliding-friction`; the feed-forward was "
                                                                     "fitted on the MJCF's 1.0).")]
    return ["", "**Floors differ between runs:** " + "; ".join(f"sliding friction {mu:g} in {', '.join(names)}"
                                                              for mu, names in sorted(runs.items()))]


def standing_lines(out):
    """Report lines of the reference the robot is told to stand in (scripts/standing_reference.py): per battery, the
    largest hip yaw and left-right knee difference at the end of a standing segment, over the seeds. Computed from
    the seed CSVs where they are (and kept in the battery's standing_reference.json, since the CSVs are not kept),
    else read from that file. The generator's standing templates give about 0 for both; the stride adaptation's
    standing_hold keeps the last steps' toe-out and split stance (docs/gco.md "Stride adaptation")."""
    rows = []
    for name in BATTERY:
        folder = os.path.join(out, name)
        path = os.path.join(folder, "standing_reference.json")
        if glob.glob(os.path.join(folder, "seed*.csv")):
            with contextlib.redirect_stdout(io.StringIO()):
                rc = standing_reference.main([folder, "--json", path])
            if rc != 0:
                raise SystemExit(f"evaluate_candidate: standing_reference.py failed on {folder}")
        if not os.path.exists(path):
            continue
        with open(path) as f:
            segments = json.load(f)["segments"]
        if not segments:
            continue
        yaw = max(segments, key=lambda r: r["hip_yaw"]["max"])
        knee = max(segments, key=lambda r: r["knee_difference"]["max"])
        rows.append(f"| {name} | {yaw['hip_yaw']['max']:.3f} ({yaw['segment']}) | "
                    f"{knee['knee_difference']['max']:.3f} ({knee['segment']}) |")
    if not rows:
        return []
    return ["", "The reference at the end of each standing segment (scripts/standing_reference.py; the standing "
                "templates give about 0):", "",
            "| battery | largest hip yaw [rad] (segment) | largest \\|knee L−R\\| [rad] (segment) |", "|---|---|---|", *rows]


def report(out):
    """Step 5: report.md from the summaries under @p out; returns its text."""
    lines = ["# Candidate against issue 12's targets", *floor_lines(out), "",
             "| battery | velocity segments in band | posture misses | coupling > 0.05 rad (largest) | runaways | falls "
             "| in band of the shaped command (slowed by the shaper) |",
             "|---|---|---|---|---|---|---|"]
    table1 = None
    for name in BATTERY:
        path = os.path.join(out, name, "summary.json")
        if not os.path.exists(path):
            lines.append(f"| {name} | not run | | | | | |")
            continue
        s = segment_band.score(path)
        lines.append(f"| {name} | {s['in_band']}/{s['velocity_segments']}"
                     f"{' (' + ', '.join(s['velocity_misses']) + ')' if s['velocity_misses'] else ''} | "
                     f"{len(s['posture_misses'])} | {len(s['coupling'])} ({s['coupling_largest']:.3f}) | "
                     f"{len(s['runaways'])} | {s['falls']} | "
                     + (f"{s['in_band_shaped']}/{s['velocity_segments']} ({s['shaper_slowed']}) |"
                        if s["in_band_shaped"] is not None else "not recorded |"))
        if name == "table1":
            with open(path) as f:
                t = json.load(f)
            table1, t1_seeds = t["mean"], [r["seed"] for r in t["runs"]]
    if table1:
        lines += ["", f"Table I (mean absolute errors against u, seeds {', '.join(map(str, t1_seeds))}):", "",
                  "| LinVel [m/s] | YawVel [rad/s] | Roll [rad] | Pitch [rad] | Height [m] | foot slip [m/s] | falls |",
                  "|---|---|---|---|---|---|---|",
                  f"| {table1['lin_vel']:.4f} | {table1['yaw_vel']:.4f} | {table1['roll']:.4f} | {table1['pitch']:.4f} | "
                  f"{table1['height']:.4f} | {table1['foot_slip']:.3f} | {table1['falls']} |"]
    lines += standing_lines(out)
    lines += stress_lines(out)
    lines += floor_stops_lines(out)
    gait = mjx_lines(out)
    if gait:
        runs = [r for r in gait if r[3] > FLIGHT_LIMIT or r[4]]
        lines += ["", f"MJX, the actor alone (crouched backward walks): flight share above {FLIGHT_LIMIT} or fallen "
                      f"in {len(runs)} of {len(gait)} crouched walks", "",
                  "| segment | v_x commanded | achieved | flight share | fallen (in it or before) |", "|---|---|---|---|---|"]
        lines += [f"| {n} | {c:+.2f} | {a:+.2f} | {f:.2f} | {'yes' if fl else 'no'} |" for n, c, a, f, fl in gait]
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write(text)
    return text


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", help="the exported ONNX actor (with its pmg.contract)")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--base-config", default="config/controller/g1_sil_policy_v20b.yaml",
                    help="controller config whose model and feed-forward are replaced (default: V20b's, the HAL at "
                         "q_rate_max 600 as in training)")
    ap.add_argument("--bin", default="build/bin", help="folder of pmg_policy_sil")
    ap.add_argument("--jobs", type=int, default=2, help="SIL runs at a time (default 2)")
    ap.add_argument("--quick", action="store_true", help="one seed per battery and one sweep: the pipeline, not a verdict")
    ap.add_argument("--mjx-actor", help="the run's actor.npz (train_config.json beside it): step 1 in MJX")
    ap.add_argument("--mjx-floor-stops", type=int, default=0, metavar="N",
                    help="with --mjx-actor: also N randomized robots on the crouched floor stops in MJX (step 1b; "
                         "two actors of 128 took one 150 s H200 call; on a CPU keep N at 32 or less: 2.5 min for wh6g on 2 cores)")
    ap.add_argument("--screen-max-fallen", type=float, default=SCREEN_MAX_FALLEN, metavar="SHARE",
                    help=f"with --mjx-floor-stops: the share of its robots (0-1) that may fall before the SIL steps are "
                         f"skipped (default {SCREEN_MAX_FALLEN}; 1 always runs them)")
    ap.add_argument("--keep-feedforward", action="store_true",
                    help="skip step 2 and keep the base config's feed-forward: the battery of a shipped config, "
                         "paired with a candidate's on the same seeds")
    ap.add_argument("--skip-stress", action="store_true",
                    help="leave out step 4b, the crouched stress sweep (72 seeds at 0.62 m, 6.5 min with --jobs 2)")
    ap.add_argument("--sliding-friction", type=float, default=None, metavar="MU",
                    help=f"run the battery and the stress sweep (steps 4, 4b) on a floor of this sliding friction "
                         f"[{FRICTION_RANGE[0]}, {FRICTION_RANGE[1]}] (default: the MJCF's {MJCF_FRICTION}); the "
                         f"feed-forward's calibration runs stay on the MJCF's floor")
    ap.add_argument("--report-only", action="store_true", help="only write report.md from the summaries in --out")
    args = ap.parse_args(argv)
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    if args.report_only:
        print(report(out))
        return 0
    if not args.model or not os.path.exists(args.model):
        ap.error(f"--model {args.model!r}: expected an existing ONNX actor")
    if args.jobs < 1:
        ap.error(f"--jobs {args.jobs}: expected 1 or more")
    args.bin = os.path.abspath(args.bin)
    model = os.path.abspath(args.model)
    base = os.path.abspath(args.base_config)
    if args.mjx_floor_stops < 0 or (args.mjx_floor_stops and not args.mjx_actor):
        ap.error(f"--mjx-floor-stops {args.mjx_floor_stops}: expected a robot count >= 1 together with --mjx-actor")
    if not 0.0 <= args.screen_max_fallen <= 1.0:
        ap.error(f"--screen-max-fallen {args.screen_max_fallen}: expected a share in [0, 1]")
    if args.sliding_friction is not None and not FRICTION_RANGE[0] <= args.sliding_friction <= FRICTION_RANGE[1]:
        ap.error(f"--sliding-friction {args.sliding_friction}: expected a sliding friction in "
                 f"[{FRICTION_RANGE[0]}, {FRICTION_RANGE[1]}]")
    if args.mjx_actor:
        print("step 1: MJX gait of the crouched backward walks", flush=True)
        mjx_gait(args, out)
        if args.mjx_floor_stops:
            print(f"step 1b: MJX, {args.mjx_floor_stops} randomized robots on the floor stops", flush=True)
            mjx_floor_stops(args, out)
            if not screen(out, args.screen_max_fallen):
                print("rejected by the MJX screen: the SIL steps are not run (--screen-max-fallen 1 runs them)", flush=True)
                print(report(out))
                return 0
    if args.keep_feedforward:
        controller = rewrite_config(base, os.path.join(out, "controller.yaml"), model, None)
        print(f"step 2 skipped (--keep-feedforward); step 3: {controller}", flush=True)
    else:
        controller = fit_feedforward(args, out, model, base)
    print(f"step 4: the battery ({', '.join(BATTERY)}), {args.jobs} at a time", flush=True)
    runs = [(os.path.join(out, name), script, first, 1 if args.quick else seeds, restart)
            for name, (script, first, seeds, restart) in BATTERY.items()]
    if not args.skip_stress:
        plan = stress_plan(args.quick)
        n = sum(p[2] for p in plan)
        print(f"step 4b: the crouched stress sweep ({n} seed{'s' if n != 1 else ''} of {STRESS[0]})", flush=True)
        runs += [(os.path.join(out, STRESS_DIR, folder), STRESS[0], first, seeds, True) for folder, first, seeds in plan]
    with ThreadPoolExecutor(args.jobs) as pool:
        list(pool.map(lambda r: sil(args, r[0], r[1], r[2], r[3], r[4], ["--controller", controller],
                                    args.sliding_friction), runs))
    print(report(out))
    return 0


def fit_feedforward(args, out, model, base):
    """Steps 2 and 3: the calibration runs, the fit, and controller.yaml with it; returns its path."""
    sweeps = [(k, first, 1) for k, first, _ in SWEEPS[:1]] if args.quick else SWEEPS
    ff = os.path.join(out, "feedforward")
    print(f"step 2: {len(sweeps)} calibration run(s) of the feed-forward", flush=True)
    with ThreadPoolExecutor(args.jobs) as pool:
        summaries = list(pool.map(lambda s: sil(args, os.path.join(ff, f"calibration_sweep{s[0]}_{s[1]}-{s[1] + s[2] - 1}"),
                                                f"config/policies/response_sweep_{s[0]}.yaml", s[1], s[2], True,
                                                ["--controller", base, "--model", model, "--feedforward", "off"]),
                                  sweeps))
    fit = os.path.join(ff, "fit.yaml")
    if not os.path.exists(fit):  # like the runs: a fit already there is the one the battery ran with
        run([sys.executable, os.path.join(HERE, "fit_command_response.py"), *summaries, "--out", fit,
             "--plot", os.path.join(ff, "fit.png")], ff, "fit.txt")
    controller = rewrite_config(base, os.path.join(out, "controller.yaml"), model, fit)
    print(f"step 3: {controller}", flush=True)
    return controller


if __name__ == "__main__":
    sys.exit(main())
