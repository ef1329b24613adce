#!/usr/bin/env python3
"""scripts/box_grip_contacts.py: on synthetic bench logs with known contacts (a success held by the
wrists alone, normal forces level; a drop with half the arms' force through the forearms, pressing the
box down 10 N; a trial that never gripped), the forearm share, the normal forces' vertical part, the
pads' share of the wrists' force, the wrists' place along the box and the time the box takes to rise
its first 5 cm (with its tilt then) come out as built, by outcome;
logs without the whole-arm columns are refused, naming the file."""
import csv
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "box_grip_contacts.py"
COLS = ["t", "phase", "grip_left_n", "grip_right_n", "arm_left_n", "arm_right_n", "arm_left_normal_up_n", "arm_right_normal_up_n",
        "grip_left_hand_n", "grip_right_hand_n", "obj_x", "obj_y", "left_hand_x", "left_hand_y", "hand_x", "hand_y",
        "obj_z", "box_tilt"]
# The box at (1, 0) in frame W, turned 90 degrees (its depth along W y, the robot at -y): the wrists
# at y = -0.1, either side of it (left x = -0.2, right x = +0.2), so 0.1 m from its centre towards the robot.
WRISTS = [1.0, 0.0, 0.8, -0.1, 1.2, -0.1]


def write_trial(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLS)
        w.writerows(rows)


def main():
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        # Trial 0's box rises 1.2 mm and turns 2 mrad per 10 ms tick of the lift: past 0.5 cm at tick 5
        # (1.05 s), past 5 cm at tick 42 (1.42 s, tilt 0.084 rad). Trials 1 and 2 stay on the table.
        write_trial(d / "trial_0.csv", [[i * 0.01, "squeeze", 30, 30, 60, 60, -50, -50, 0, 0] + WRISTS + [0.6, 0] for i in range(50)] +  # not the lift: ignored
                    [[1 + i * 0.01, "lift", 20, 20, 20, 20, 0.5, 0.5, 20, 20] + WRISTS + [0.6 + 0.0012 * i, 0.002 * i] for i in range(100)])
        write_trial(d / "trial_1.csv", [[i * 0.01, "lift", 15, 15, 30, 30, -6.0, -4.0, 3, 3] + WRISTS + [0.6, 0] for i in range(100)] +
                    [[2 + i * 0.01, "lift", 0, 0, 2, 2, 0, 0, 0, 0] + WRISTS + [0.6, 0] for i in range(100)])  # below 5 N: not a grip
        write_trial(d / "trial_2.csv", [[i * 0.01, "lift", 0, 0, 0, 0, 0, 0, 0, 0] + WRISTS + [0.6, 0] for i in range(100)])
        (d / "summary.json").write_text(json.dumps({
            "trial_results": [{"trial": 0, "success": True}, {"trial": 1, "success": False}, {"trial": 2, "success": False}],
            "failures": [{"trial": 1, "reason": "dropped"}, {"trial": 2, "reason": "not_lifted"}]}))
        r = subprocess.run([sys.executable, str(SCRIPT), f"syn={d}", "--json", str(d / "out.json")], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
        rep = json.loads((d / "out.json").read_text())["syn"]
        t = {x["trial"]: x for x in rep["trials"]}
        assert abs(t[0]["forearm_share"]) < 1e-9 and abs(t[0]["normal_up_n"] - 1.0) < 1e-9, t[0]
        assert abs(t[1]["forearm_share"] - 0.5) < 1e-9 and abs(t[1]["normal_up_n"] + 10.0) < 1e-9, t[1]
        assert abs(t[0]["pad_share"] - 1.0) < 1e-9 and abs(t[1]["pad_share"] - 0.2) < 1e-9, (t[0], t[1])
        assert abs(t[0]["wrists_along_box_m"] + 0.1) < 1e-9, t[0]
        assert abs(t[0]["first_5cm_s"] - 0.37) < 1e-9 and abs(t[0]["tilt_at_5cm_rad"] - 0.084) < 1e-9, t[0]
        assert t[1]["first_5cm_s"] is None and t[1]["tilt_at_5cm_rad"] is None, t[1]
        assert t[2]["forearm_share"] is None and t[2]["pad_share"] is None and "no grip while lifting" in r.stdout
        s = rep["summary"]
        assert s["trials"] == 3 and s["successes"] == 1
        assert s["by_outcome"]["dropped"]["forearm_share_above_0.3"] == 1 and s["by_outcome"]["all"]["trials"] == 2
        assert abs(s["by_outcome"]["success"]["pad_share_median"] - 1.0) < 1e-9
        assert abs(s["by_outcome"]["success"]["first_5cm_s_median"] - 0.37) < 1e-9 and s["by_outcome"]["dropped"]["first_5cm_s_median"] is None
        # An older log, without the whole-arm columns, is refused by name.
        with open(d / "trial_0.csv", "w") as f:
            f.write("t,phase,grip_left_n,grip_right_n\n0,lift,1,1\n")
        r = subprocess.run([sys.executable, str(SCRIPT), f"syn={d}"], capture_output=True, text=True)
        assert r.returncode != 0 and "trial_0.csv" in r.stderr and "arm_left_n" in r.stderr, r.stderr
    print("box_grip_contacts: forearm share, normal forces' vertical part, pad share, wrists' place and the first 5 cm as built")


if __name__ == "__main__":
    main()
