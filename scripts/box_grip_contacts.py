#!/usr/bin/env python3
"""Where the arms hold the box while lifting, per trial and per outcome, from pmg_teleop_bench's logs.

  scripts/box_grip_contacts.py [--json FILE] NAME=DIR[,DIR...] [NAME=DIR...]

Each DIR is a `pmg_teleop_bench --task box --out DIR` folder (summary.json, trial_<k>.csv). Over the
lift phase's ticks where the arms press on the box (whole-arm normal force above 5 N), each trial gets:
- forearm share: the part of the arms' normal force on the box that goes through links above the wrist
  roll joint (elbow and forearm), 1 - sum(grip_*_n) / sum(arm_*_n);
- normal up: the median vertical part (frame W, up +) of the arms' normal forces on the box [N];
  negative: the arms press the box down (as where they lie across its top edges) and friction must
  carry that as well as the weight.
Trials with fewer than 10 such ticks (no grip while lifting) are listed without numbers. Prints one
line per trial and, per NAME, the medians by outcome; --json writes them.
"""
import argparse
import csv
import json
import statistics as st
import sys
from pathlib import Path


def trial_outcomes(d):
    s = json.loads((d / "summary.json").read_text())
    reasons = {f["trial"]: f["reason"] for f in s["failures"]}
    return {t["trial"]: ("success" if t["success"] else reasons.get(t["trial"], "failed")) for t in s["trial_results"]}


def analyse_trial(csv_path):
    rows = list(csv.DictReader(open(csv_path)))
    need = ("arm_left_n", "arm_right_n", "grip_left_n", "grip_right_n", "arm_left_normal_up_n", "arm_right_normal_up_n")
    if rows and any(k not in rows[0] for k in need):
        sys.exit(f"{csv_path}: lacks the whole-arm contact columns ({', '.join(need)}): a log from an older pmg_teleop_bench")
    f = lambda r, k: float(r[k])
    lift = [r for r in rows if r["phase"] == "lift" and f(r, "arm_left_n") + f(r, "arm_right_n") > 5.0]
    if len(lift) < 10:
        return None, None
    arm = sum(f(r, "arm_left_n") + f(r, "arm_right_n") for r in lift)
    wrist = sum(f(r, "grip_left_n") + f(r, "grip_right_n") for r in lift)
    normal_up = st.median(f(r, "arm_left_normal_up_n") + f(r, "arm_right_normal_up_n") for r in lift)
    return 1.0 - wrist / arm, normal_up


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", nargs="+", help="NAME=DIR[,DIR...]")
    p.add_argument("--json", default="")
    a = p.parse_args()
    report = {}
    for spec in a.runs:
        name, _, dirs = spec.partition("=")
        if not dirs:
            sys.exit(f"{spec}: expected NAME=DIR[,DIR...]")
        trials = []
        for d in (Path(x) for x in dirs.split(",")):
            if not (d / "summary.json").exists():
                sys.exit(f"{d}: no summary.json (a pmg_teleop_bench --task box output folder)")
            for k, outcome in sorted(trial_outcomes(d).items()):
                share, up = analyse_trial(d / f"trial_{k}.csv")
                trials.append({"dir": str(d), "trial": k, "outcome": outcome, "forearm_share": share, "normal_up_n": up})
                print(f"{name} {d}/trial_{k}: {outcome:16s} " +
                      (f"forearm share {share:4.2f}, normal up {up:+6.1f} N" if share is not None else "no grip while lifting"))
        summary = {"trials": len(trials), "successes": sum(t["outcome"] == "success" for t in trials), "by_outcome": {}}
        gripped = [t for t in trials if t["forearm_share"] is not None]
        for outcome in sorted({t["outcome"] for t in gripped}) + ["all"]:
            g = [t for t in gripped if outcome == "all" or t["outcome"] == outcome]
            summary["by_outcome"][outcome] = {
                "trials": len(g),
                "forearm_share_median": st.median(t["forearm_share"] for t in g),
                "normal_up_n_median": st.median(t["normal_up_n"] for t in g),
                "forearm_share_above_0.3": sum(t["forearm_share"] > 0.3 for t in g)}
        print(f"== {name}: {summary['successes']}/{summary['trials']} successes")
        for outcome, v in summary["by_outcome"].items():
            print(f"   {outcome:16s} {v['trials']:3d} gripped: forearm share median {v['forearm_share_median']:.2f} "
                  f"({v['forearm_share_above_0.3']} above 0.3), normal up median {v['normal_up_n_median']:+.1f} N")
        report[name] = {"summary": summary, "trials": trials}
    if a.json:
        Path(a.json).write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
