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
- pad share: the part of the wrist subtrees' normal force that goes through the rubber hands' pads
  (the scene's `*_hand_collision` geoms) rather than the wrist housings, sum(grip_*_hand_n) /
  sum(grip_*_n); logs without those columns give none;
- wrists along the box: at the first such tick, the midpoint of the two wrists (`*_wrist_yaw_link`)
  along the box's depth from its centre, frame W horizontal, the box's depth axis taken
  perpendicular to the line between the wrists (they sit on its two sides) [m]; negative: towards
  the robot (the box is 0.22 m deep, so -0.11 is its near side).
- first 5 cm: lifting or carrying, the time the box's centre takes from 0.5 cm to 5 cm above where it
  started (`obj_z`) [s], and the box's tilt (`box_tilt`) when it gets there [rad]: how fast the box
  leaves the table, and how far it has turned in the grip by then; none where it never rose 5 cm.
Trials with fewer than 10 such ticks (no grip while lifting) are listed without the force numbers. Prints one
line per trial and, per NAME, the medians by outcome; --json writes them.
"""
import argparse
import csv
import json
import math
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
    out = {"forearm_share": None, "normal_up_n": None, "pad_share": None, "wrists_along_box_m": None, **first_5cm(rows)}
    lift = [r for r in rows if r["phase"] == "lift" and f(r, "arm_left_n") + f(r, "arm_right_n") > 5.0]
    if len(lift) < 10:
        return out
    arm = sum(f(r, "arm_left_n") + f(r, "arm_right_n") for r in lift)
    wrist = sum(f(r, "grip_left_n") + f(r, "grip_right_n") for r in lift)
    out["forearm_share"] = 1.0 - wrist / arm
    out["normal_up_n"] = st.median(f(r, "arm_left_normal_up_n") + f(r, "arm_right_normal_up_n") for r in lift)
    if "grip_left_hand_n" in rows[0] and wrist > 0:
        out["pad_share"] = sum(f(r, "grip_left_hand_n") + f(r, "grip_right_hand_n") for r in lift) / wrist
    if all(k in rows[0] for k in ("obj_x", "obj_y", "left_hand_x", "left_hand_y", "hand_x", "hand_y")):
        r = lift[0]
        ly, lx = f(r, "left_hand_y") - f(r, "hand_y"), f(r, "left_hand_x") - f(r, "hand_x")
        n = math.hypot(lx, ly)
        if n > 1e-6:  # depth axis: the right-to-left wrist line turned -90 degrees about z, forward (frame W)
            mx = 0.5 * (f(r, "left_hand_x") + f(r, "hand_x")) - f(r, "obj_x")
            my = 0.5 * (f(r, "left_hand_y") + f(r, "hand_y")) - f(r, "obj_y")
            out["wrists_along_box_m"] = (mx * ly - my * lx) / n
    return out


def first_5cm(rows):
    """Lifting or carrying: the seconds from the box's centre 0.5 cm to 5 cm above its first logged
    height, and its tilt at 5 cm (None, None where the log lacks obj_z/box_tilt or it never got there)."""
    none = {"first_5cm_s": None, "tilt_at_5cm_rad": None}
    if not rows or "obj_z" not in rows[0] or "box_tilt" not in rows[0]:
        return none
    z0 = float(rows[0]["obj_z"])
    up = [r for r in rows if r["phase"] in ("lift", "carry")]
    a = next((r for r in up if float(r["obj_z"]) - z0 > 0.005), None)
    b = next((r for r in up if float(r["obj_z"]) - z0 > 0.05), None)
    if a is None or b is None:
        return none
    return {"first_5cm_s": float(b["t"]) - float(a["t"]), "tilt_at_5cm_rad": float(b["box_tilt"])}


def fmt_or_dash(v, spec):
    """A number in `spec`, or '-' where the log could not give it."""
    return "-" if v is None else format(v, spec)


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
                res = analyse_trial(d / f"trial_{k}.csv")
                trials.append({"dir": str(d), "trial": k, "outcome": outcome, **res})
                print(f"{name} {d}/trial_{k}: {outcome:16s} " +
                      (f"forearm share {res['forearm_share']:4.2f}, normal up {res['normal_up_n']:+6.1f} N, "
                       f"pad share {fmt_or_dash(res['pad_share'], '4.2f')}, wrists along the box {fmt_or_dash(res['wrists_along_box_m'], '+.3f')} m"
                       if res["forearm_share"] is not None else "no grip while lifting") +
                      f"; first 5 cm in {fmt_or_dash(res['first_5cm_s'], '.2f')} s, tilt then {fmt_or_dash(res['tilt_at_5cm_rad'], '.2f')} rad")
        summary = {"trials": len(trials), "successes": sum(t["outcome"] == "success" for t in trials), "by_outcome": {}}
        gripped = [t for t in trials if t["forearm_share"] is not None]
        for outcome in sorted({t["outcome"] for t in gripped}) + ["all"]:
            g = [t for t in gripped if outcome == "all" or t["outcome"] == outcome]
            summary["by_outcome"][outcome] = {
                "trials": len(g),
                "forearm_share_median": st.median(t["forearm_share"] for t in g),
                "normal_up_n_median": st.median(t["normal_up_n"] for t in g),
                "forearm_share_above_0.3": sum(t["forearm_share"] > 0.3 for t in g)}
            for key in ("pad_share", "wrists_along_box_m", "first_5cm_s", "tilt_at_5cm_rad"):
                v = [t[key] for t in g if t[key] is not None]
                summary["by_outcome"][outcome][key + "_median"] = st.median(v) if v else None
        print(f"== {name}: {summary['successes']}/{summary['trials']} successes")
        for outcome, v in summary["by_outcome"].items():
            print(f"   {outcome:16s} {v['trials']:3d} gripped: forearm share median {v['forearm_share_median']:.2f} "
                  f"({v['forearm_share_above_0.3']} above 0.3), normal up median {v['normal_up_n_median']:+.1f} N, "
                  f"pad share median {fmt_or_dash(v['pad_share_median'], '.2f')}, "
                  f"wrists along the box median {fmt_or_dash(v['wrists_along_box_m_median'], '+.3f')} m, "
                  f"first 5 cm median {fmt_or_dash(v['first_5cm_s_median'], '.2f')} s at tilt {fmt_or_dash(v['tilt_at_5cm_rad_median'], '.2f')} rad")
        report[name] = {"summary": summary, "trials": trials}
    if a.json:
        Path(a.json).write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
