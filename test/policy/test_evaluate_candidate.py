#!/usr/bin/env python3
"""Tests scripts/evaluate_candidate.py without running the SIL (ctest evaluate_candidate_config_and_report,
label unit):
- its controller.yaml for V20e (V20b's config, V20e's actor, V20e's feed-forward fit) loads to the same
  settings as the one written by hand in training/results/fidelity/seeds_V20b/V20e/controller.yaml
  (every path resolved from its own file), although written into another folder;
- a base config without a policy or a feed-forward block is refused, naming what is missing;
- with --keep-feedforward (no fit) the base's feed-forward stays, only the model and paths change;
- the report of V20e's committed summaries (grid seeds 0-11, Table I seeds 0-4, crouched backward)
  gives V20e's grid 28/33 in band, its Table I means from the summary, and "not run" for the
  batteries that are missing; a synthetic MJX gait file with one crouched walk in flight 0.35, one that
  fell and one after the fall (NaN means) is reported as 3 of 4 crouched walks flagged (the standing
  walk and the stop left out);
- the crouched stress sweep is planned as 6 runs of 12 seeds (0-71; one seed with --quick), and reported
  from N24g's committed sweep summaries as 29 of 72 runs with a fall, each fall named by the segment it
  happened in (seed 2: 46.57 s in stand_left_0.2, 53.96 s in stand_left_0.3; 12 in stand_left_0.3);
- a synthetic MJX floor-stops rollout of 5 robots, 3 fallen in two segments, is reported as 3 of 5 with
  the segments; --mjx-floor-stops without --mjx-actor is refused;
- the screen: with that rollout in place, an evaluation with --mjx-floor-stops stops after step 1b (3 of 5 is
  above the default 10 %), runs no SIL step, and its report says it was rejected; at a share of 0.6 the same
  rollout passes; a share outside [0, 1] is refused.
- the floor: --sliding-friction 0.4 with a stand-in pmg_policy_sil (it writes V20e's grid summary with the
  floor_friction its argv asked for) runs every battery with --sliding-friction 0.4 on its command line and
  the report names the floor 0.4; run again with no friction, the same folder is refused (its summaries ran on
  0.4), and 0.05 is refused before anything runs; the report of summaries without floor_friction names the
  MJCF's 1.0, and one of mixed floors names each floor with its runs.
- the standing reference: a grid folder with one seed CSV whose reference holds 0.35 rad of hip yaw in its last
  standing segment gets the report's standing table row (0.350, that segment) and a standing_reference.json; with
  the CSV deleted (the results' folders keep no CSVs) the report reads the same row from that file; a battery
  with neither has no row.
Usage: test_evaluate_candidate.py
"""
import json
import os
import shutil
import sys
import tempfile

import numpy as np
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import evaluate_candidate as ec  # noqa: E402
from script_checks import Checks  # noqa: E402  (beside this file)
from test_standing_reference import write_seed  # noqa: E402  (beside this file)

V20E = os.path.join(ROOT, "training", "results", "fidelity", "seeds_V20b", "V20e")
N24G_SWEEP = os.path.join(ROOT, "training", "results", "fidelity", "exploration_noise", "N24g", "sweep_0.62")
check = Checks()


def resolved(path):
    """The config at @p path with its file paths made absolute."""
    with open(path) as f:
        c = yaml.safe_load(f)
    here = os.path.dirname(os.path.abspath(path))
    for key in ec.PATH_KEYS:
        c[key] = os.path.normpath(os.path.join(here, c[key]))
    c["policy"]["model"] = os.path.normpath(os.path.join(here, c["policy"]["model"]))
    return c


def refused(argv):
    """Whether ec.main(@p argv) stops with argparse's usage error (exit status 2)."""
    try:
        ec.main(argv)
    except SystemExit as e:
        return e.code == 2
    return False


FAKE_SIL = """#!/usr/bin/env python3
import json, sys
argv = sys.argv[1:]
out = argv[argv.index("--out") + 1]
with open(sys.argv[0] + ".summary") as f:
    summary = json.load(f)
summary["floor_friction"] = float(argv[argv.index("--sliding-friction") + 1]) if "--sliding-friction" in argv else 1.0
with open(out + "/summary.json", "w") as f:
    json.dump(summary, f)
"""


def floor_checks(tmp):
    """--sliding-friction through main() with a stand-in pmg_policy_sil, the refusal to mix floors, the report's
    floor line."""
    fake = os.path.join(tmp, "fake_bin")
    os.makedirs(fake)
    sil = os.path.join(fake, "pmg_policy_sil")
    with open(sil, "w") as f:
        f.write(FAKE_SIL)
    os.chmod(sil, 0o755)
    shutil.copy(os.path.join(V20E, "grid_0-11_summary.json"), sil + ".summary")
    ev = os.path.join(tmp, "floor")
    argv = ["--model", os.path.join(V20E, "g1_pmg_policy.onnx"), "--out", ev, "--bin", fake, "--keep-feedforward",
            "--skip-stress", "--base-config", os.path.join(ROOT, "config", "controller", "g1_sil_policy.yaml")]
    rc = ec.main(argv + ["--sliding-friction", "0.4"])
    lines = [open(os.path.join(ev, name, "command.txt")).read() for name in ec.BATTERY]
    text = open(os.path.join(ev, "report.md")).read()
    check(rc == 0 and len(lines) == len(ec.BATTERY) and all("--sliding-friction 0.4 " in c for c in lines)
          and "Floor: sliding friction **0.4** in every SIL run" in text,
          f"--sliding-friction 0.4: every battery run asked for it ({len(lines)} command lines) and the report names it")
    try:
        ec.main(argv)
        msg = ""
    except RuntimeError as e:
        msg = str(e)
    check("ran on a floor of sliding friction 0.4, not the 1.0 asked for" in msg,
          f"summaries from another floor are refused, not reused: {msg[:90]}")
    e5 = os.path.join(tmp, "e5")
    check(refused(["--model", argv[1], "--out", e5, "--bin", fake, "--sliding-friction", "0.05"])
          and not os.path.exists(os.path.join(e5, "grid")),
          "--sliding-friction 0.05 is refused")
    mixed = os.path.join(tmp, "mixed")
    for name, mu in (("grid", 0.4), ("mirror", None)):
        os.makedirs(os.path.join(mixed, name))
        with open(os.path.join(V20E, "grid_0-11_summary.json")) as f:
            summary = json.load(f)
        if mu is not None:
            summary["floor_friction"] = mu
        with open(os.path.join(mixed, name, "summary.json"), "w") as f:
            json.dump(summary, f)
    check("**Floors differ between runs:** sliding friction 0.4 in grid; sliding friction 1 in mirror" in ec.report(mixed),
          "report: runs on two floors are named, each with its runs")


def standing_checks(tmp):
    """The report's standing-reference table from seed CSVs, then from the standing_reference.json they left."""
    out = os.path.join(tmp, "standing")
    grid = os.path.join(out, "grid")
    os.makedirs(grid)
    os.makedirs(os.path.join(out, "mirror"))  # neither CSVs nor the json: no row
    # stand, a walk, then stand_2 with the right hip yawed by the 0.35 rad the last steps left (knees level)
    write_seed(grid, 0, yaw_r=-0.35, roll_l=0.0, knee_l=0.3)
    row = "| grid | 0.350 (stand_2) | 0.000 (stand) |"
    text = ec.report(out)
    check(row in text and os.path.exists(os.path.join(grid, "standing_reference.json")) and "| mirror | 0" not in text,
          "report: the standing reference from the seed CSVs (hip yaw 0.350 in stand_2), kept in standing_reference.json")
    os.remove(os.path.join(grid, "seed0.csv"))
    check(row in ec.report(out), "report: the same row from standing_reference.json once the CSVs are gone")


def main():
    tmp = tempfile.mkdtemp(prefix="pmg_eval_candidate_")
    try:
        out = os.path.join(tmp, "a", "b")
        os.makedirs(out)
        generated = ec.rewrite_config(os.path.join(ROOT, "config", "controller", "g1_sil_policy_v20b.yaml"),
                                      os.path.join(out, "controller.yaml"), os.path.join(V20E, "g1_pmg_policy.onnx"),
                                      os.path.join(V20E, "feedforward", "fit.yaml"))
        mine, by_hand = resolved(generated), resolved(os.path.join(V20E, "controller.yaml"))
        differ = sorted(k for k in set(mine) | set(by_hand) if mine.get(k) != by_hand.get(k))
        check(not differ and os.path.exists(mine["policy"]["model"]) and os.path.isdir(mine["clips"]),
              f"controller.yaml for V20e = the hand-written one (keys that differ: {differ or 'none'}); "
              f"model {os.path.relpath(mine['policy']['model'], ROOT)}")
        shipped = os.path.join(ROOT, "config", "controller", "g1_sil_policy.yaml")
        kept = resolved(ec.rewrite_config(shipped, os.path.join(out, "kept.yaml"), os.path.join(V20E, "g1_pmg_policy.onnx"),
                                          None))
        base = resolved(shipped)
        differ = sorted(k for k in set(kept) | set(base) if k != "policy" and kept.get(k) != base.get(k))
        check(not differ and kept["velocity_feedback"]["feedforward"] == base["velocity_feedback"]["feedforward"]
              and kept["policy"]["model"].endswith("V20e/g1_pmg_policy.onnx"),
              f"--keep-feedforward: the shipped config's feed-forward and every other key kept, the model replaced "
              f"(keys that differ: {differ or 'none'})")
        try:
            ec.rewrite_config(os.path.join(ROOT, "config", "controller", "g1_sil.yaml"), os.path.join(out, "x.yaml"),
                              os.path.join(V20E, "g1_pmg_policy.onnx"), os.path.join(V20E, "feedforward", "fit.yaml"))
            msg = ""
        except ValueError as e:
            msg = str(e)
        check("g1_sil.yaml" in msg and "policy.model" in msg and "feedforward.vx" in msg,
              f"a base config without a policy is refused, naming it: {msg[:120]}")

        ev = os.path.join(tmp, "eval")
        for name, src in (("grid", "grid_0-11_summary.json"), ("table1", "t1_0-4_summary.json"),
                          ("crouched_backward", "crouched_backward_summary.json")):
            os.makedirs(os.path.join(ev, name))
            shutil.copy(os.path.join(V20E, src), os.path.join(ev, name, "summary.json"))
        names = ["back0.3_0.78", "back0.3_0.74", "stop_0.74", "back0.5_0.74", "back0.5_0.7", "back0.3_0.7"]
        cmd = np.zeros((6, 6))
        cmd[:, 0] = [-0.3, -0.3, 0.0, -0.5, -0.5, -0.3]
        cmd[:, 5] = [0.78, 0.74, 0.74, 0.74, 0.70, 0.70]
        ach = cmd.copy()
        gait = np.zeros((6, 4))
        gait[:, 0] = [0.40, 0.10, 0.0, 0.35, 0.05, 0.0]
        ach[5], gait[5] = np.nan, np.nan  # after the fall: no robot in its window
        np.savez(os.path.join(ev, "mjx_crouched_backward.npz"), segment_names=np.array(names), segment_command=cmd,
                 segment_achieved=ach, segment_gait=gait, segment_falls=np.array([0, 0, 0, 0, 1, 0]))
        plan = ec.stress_plan()
        check([p[0] for p in plan] == [f"seeds{k}-{k + 11}" for k in range(0, 72, 12)] and
              all(p[2] == 12 for p in plan) and ec.stress_plan(quick=True) == [("seeds0-0", 0, 1)],
              f"stress sweep: 6 runs of 12 seeds, one seed with --quick ({plan[0]}, ..., {plan[-1]})")
        for folder, _, _ in plan:
            os.makedirs(os.path.join(ev, ec.STRESS_DIR, folder))
            shutil.copy(os.path.join(N24G_SWEEP, folder, "summary.json"), os.path.join(ev, ec.STRESS_DIR, folder))
        runs = dict(ec.stress_runs(ev))
        check(len(runs) == 72 and runs[2] == [(46.57, "stand_left_0.2"), (53.96, "stand_left_0.3")] and runs[0] == [],
              f"stress sweep: 72 runs read, seed 2's falls named by segment ({runs.get(2)})")
        np.savez(os.path.join(ev, "mjx_floor_stops.npz"), done=np.zeros((5, 40)),
                 segment_names=np.array(["stand", "left0.2_0.66", "stop_left0.2_0.66", "stand_left0.2_0.62"]),
                 segment_falls=np.array([0, 1, 0, 2]))
        text = ec.main(["--report-only", "--out", ev]) == 0 and open(os.path.join(ev, "report.md")).read()
        check("on the floor stops (training/results/fidelity/crouched/floor_stops_0.62.yaml, --seed 1): **3 of 5** "
              "(left0.2_0.66 1, stand_left0.2_0.62 2)" in text, "report: MJX floor stops, 3 of 5 robots fallen, by segment")
        check("Floor: sliding friction **1** in every SIL run of the battery and the stress sweep (the MJCF's)." in text,
              "report: summaries without floor_friction ran on the MJCF's floor")
        check(refused(["--model", os.path.join(V20E, "g1_pmg_policy.onnx"), "--out", os.path.join(tmp, "e2"),
                       "--mjx-floor-stops", "32"]) and not os.path.exists(os.path.join(tmp, "e2", "grid")),
              "--mjx-floor-stops without --mjx-actor is refused before anything runs")
        e3 = os.path.join(tmp, "e3")
        os.makedirs(e3)
        for name in ("mjx_crouched_backward.npz", "mjx_floor_stops.npz"):  # step 1 and 1b's rollouts, already there
            shutil.copy(os.path.join(ev, name), e3)
        rc = ec.main(["--model", os.path.join(V20E, "g1_pmg_policy.onnx"), "--out", e3, "--bin", os.path.join(tmp, "no_bin"),
                      "--mjx-actor", os.path.join(tmp, "unused", "actor.npz"), "--mjx-floor-stops", "5"])
        with open(os.path.join(e3, "screen.json")) as f:
            verdict = json.load(f)
        rejected = open(os.path.join(e3, "report.md")).read()
        check(rc == 0 and verdict == {"fallen": 3, "robots": 5, "max_share": 0.1, "passed": False}
              and sorted(os.listdir(e3)) == ["mjx_crouched_backward.npz", "mjx_floor_stops.npz", "report.md", "screen.json"]
              and "**Rejected by the MJX screen** (60 % of the robots fell, 10 % allowed" in rejected,
              f"screen: 3 of 5 fallen is rejected at the default share, no SIL step run ({sorted(os.listdir(e3))})")
        check(ec.screen(e3, 0.6) and "**Passed the MJX screen** (60 % of the robots fell, 60 % allowed)." in
              ec.report(e3), "screen: the same rollout passes at a share of 0.6")
        check(refused(["--model", os.path.join(V20E, "g1_pmg_policy.onnx"), "--out", os.path.join(tmp, "e4"),
                       "--screen-max-fallen", "1.5"]) and not os.path.exists(os.path.join(tmp, "e4", "grid")),
              "--screen-max-fallen 1.5 is refused")
        check("runs with a fall **29 of 72** (seeds 2, 8, 9," in text and "stand_left_0.3 12, stand_left_0.2 8" in text,
              "report: N24g's stress sweep, 29 of 72 runs with a fall, the falls by segment")
        with open(os.path.join(V20E, "t1_0-4_summary.json")) as f:
            t1 = json.load(f)["mean"]
        rows = {line.split("|")[1].strip(): line for line in text.splitlines() if line.startswith("| ")}
        check(rows.get("grid", "").startswith("| grid | 28/33") and rows["grid"].endswith("| not recorded |")
              and "not run" in rows.get("mirror", "") and
              "not run" in rows.get("posture_walks", ""),
              f"report: V20e's grid 28/33, mirror and posture walks not run ({rows.get('grid', '')[:40]})")
        check(f"| {t1['lin_vel']:.4f} | {t1['yaw_vel']:.4f} |" in text and rows.get("table1", "").startswith("| table1 | 9/9")
              and "seeds 0, 1, 2, 3, 4)" in text,
              f"report: Table I means from the summary (LinVel {t1['lin_vel']:.4f}) and 9/9 in band")
        check("in 3 of 4 crouched walks" in text and "| back0.5_0.7 | -0.50 | -0.50 | 0.05 | yes |" in text and
              "| back0.3_0.74 | -0.30 | -0.30 | 0.10 | no |" in text and "| back0.3_0.7 | -0.30 | +nan | nan | yes |" in text
              and "back0.3_0.78" not in text and "stop_0.74" not in text,
              "report: MJX gait, 3 of 4 crouched walks flagged (flight 0.35, a fall, one after the fall); standing walk "
              "and stop left out")
        floor_checks(tmp)
        standing_checks(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return check.exit_code()


if __name__ == "__main__":
    sys.exit(main())
