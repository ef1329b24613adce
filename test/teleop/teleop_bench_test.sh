#!/usr/bin/env bash
# pmg_teleop_bench (issue 14) runs 2 randomised wiping trials end to end (scene drawn, ControllerApp
# in lockstep, scripted operator through the VR stream, object judged) and reports truthfully:
# summary.json has the issue's keys, each trial's verdict agrees with the object trajectory in its
# CSV (the lateral path recomputed here from the CSV, 1 cm steps, and the on-table check), every
# failure carries a known class, the two trials drew different towel places, both trials meet the
# paper's criterion (the towel moved laterally more than 1 m on the top, the robot standing), the first
# success gets its frame strip and trace plot (only its event log is kept), the hand wipes palm down
# with the scene's hand pad carrying most of the push on the towel and wipes by arm strokes (the
# hand sweeps to and fro in the room while the pelvis stays nearly put), the robot walks in upright
# and crouches only at the table, and a bad
# --operator file is refused naming the file and key. (20 trials succeed at the rate docs/teleop.md
# reports; these two, seeds 1 and 2, are among the successes with the shipped operator and controller,
# one with each hand.)
#   teleop_bench_test.sh BIN_DIR
set -euo pipefail
bin="${1:?usage: teleop_bench_test.sh BIN_DIR}"
d="$(mktemp -d)"
trap 'rm -rf "$d"' EXIT
"$bin/pmg_teleop_bench" --task wipe --trials 2 --seed 1 --out "$d/out" > "$d/log.txt"
cat "$d/log.txt"
PYTHONPATH="$(dirname "${BASH_SOURCE[0]}")" python3 - "$d/out" <<'PY'
import csv, json, os, sys
from bench_figures import missing_figure_files
out = sys.argv[1]
s = json.load(open(os.path.join(out, "summary.json")))
fail = []
for k in ("task", "trials", "successes", "success_rate", "failures", "paper_success_rate"):
    if k not in s:
        fail.append(f"summary.json lacks {k}")
if s["trials"] != 2 or len(s["trial_results"]) != 2 or s["successes"] + len(s["failures"]) != 2:
    fail.append(f"trial counts: {s['trials']}, {len(s['trial_results'])}, {s['successes']} + {len(s['failures'])}")
known = {"loss_of_balance", "left_the_table", "too_short"}
for f in s["failures"]:
    if f["reason"] not in known:
        fail.append(f"unknown failure class {f['reason']}")
starts = []
for r in s["trial_results"]:
    # The trunk against a table (the pelvis or torso touching one): reported per trial, in the detail
    # too; -1 / 0 when it never touched (wiping bent over the table, it may lean on it).
    ts, tn = r.get("trunk_on_table_s"), r.get("trunk_on_table_n")
    if ts is None or tn is None or (ts >= 0) != (tn > 0) or (ts >= 0) != ("trunk touched a table" in r["detail"]):
        fail.append(f"trial {r['trial']}: trunk_on_table_s {ts}, trunk_on_table_n {tn} and the detail disagree")
    rows = list(csv.DictReader(open(os.path.join(out, f"trial_{r['trial']}.csv"))))
    ys = [float(x["obj_y"]) for x in rows]   # the table is not rotated: y in W = y along the table
    starts.append(ys[0])
    anchor, path = ys[0], 0.0
    for y in ys:
        if abs(y - anchor) >= 0.01:
            path += abs(y - anchor)
            anchor = y
    if abs(path - r["measure"]) > 0.02 + 0.03 * path:  # the CSV's 0.1 mm rounding moves 1 cm steps
        fail.append(f"trial {r['trial']}: judged path {r['measure']:.3f} m, CSV path {path:.3f} m")
    on_top = min(float(x["obj_z"]) for x in rows) > 0.6  # the top is at 0.67 m; off it the towel drops to the floor
    # The shipped operator wipes palm down: while wiping, the hand's palm faces the table and the
    # scene's hand pad, not the wrist housing, carries most of the push on the towel.
    wiping = [x for x in rows if x["phase"] == "wipe"]
    flat = sorted(abs(float(x["palm_normal_z"])) for x in wiping)
    if not wiping or flat[len(flat) // 2] < 0.8:
        fail.append(f"trial {r['trial']}: the palm is not down while wiping (median |palm_normal_z| {flat[len(flat) // 2] if flat else None})")
    push = sum(float(x["press_n"]) for x in wiping)
    pad = sum(float(x["press_pad_n"]) for x in wiping)
    if not push > 0 or pad < 0.5 * push:
        fail.append(f"trial {r['trial']}: the pad carries {pad:.0f} of {push:.0f} N*ticks of the push on the towel")
    # Arm strokes (stroke_m 0.12 in the shipped operator): the hand sweeps to and fro in the room
    # (direction reversals counted in 3 cm steps) while the pelvis stays nearly put. Walking
    # sideways with the hand on the towel (the previous operator) reversed 4-8 times in 90 s with
    # the pelvis ranging farther than the hand; strokes reversed 14-41 times with the pelvis
    # within 0.04-0.10 m and the hand over 0.25-0.29 m (seeds 1, 2, 20, 21).
    hy = [float(x["hand_y"]) for x in wiping]
    py = [float(x["pelvis_y"]) for x in wiping]
    reversals, direction, anchor = 0, 0, hy[0] if hy else 0.0
    for y in hy:
        if abs(y - anchor) >= 0.03:
            sgn = 1 if y > anchor else -1
            reversals += direction != 0 and sgn != direction
            direction, anchor = sgn, y
    if not hy or reversals < 10 or max(py) - min(py) > 0.6 * (max(hy) - min(hy)):
        fail.append(f"trial {r['trial']}: no arm strokes while wiping ({reversals} reversals of the hand; pelvis over "
                    f"{max(py) - min(py) if py else 0:.3f} m, hand over {max(hy) - min(hy) if hy else 0:.3f} m)")
    # The shipped operator walks in upright and crouches only at the table (crouch_in_place):
    # crouched while walking in, the robot overshot its place into the table. Standing, the pelvis is
    # at about 0.78 m; crouched 0.15 m, about 0.65 m (seeds 0-39: 0.771-0.775 walking in, 0.644-0.649
    # wiping). Every trial reports how often it stood up and stepped back, pinned (unpin_m).
    walk_in = [float(x["pelvis_z"]) for x in rows if x["phase"] == "close_in"]
    wipe_z = sorted(float(x["pelvis_z"]) for x in wiping)
    if not walk_in or min(walk_in) < 0.74 or not wipe_z or wipe_z[len(wipe_z) // 2] > 0.70:
        fail.append(f"trial {r['trial']}: not upright walking in (lowest pelvis {min(walk_in) if walk_in else None}) or "
                    f"not crouched wiping (median pelvis {wipe_z[len(wipe_z) // 2] if wipe_z else None})")
    if not isinstance(r.get("unpins"), int) or r["unpins"] < 0:
        fail.append(f"trial {r['trial']}: trial_results lacks unpins")
    if r["success"] != (r["measure"] > 1.0 and path > 0.95 and not r["fell"] and on_top):
        fail.append(f"trial {r['trial']}: verdict {r['success']} disagrees with the trajectory (path {path:.3f} m)")
if s["successes"] != 2:
    fail.append(f"{s['successes']} of 2 trials met the criterion: {[f['reason'] for f in s['failures']]}")
# Figures of the first success (both trials succeed: no failure figure): a frame strip rendered by
# pmg_render_log over the trial's scene with the towel from its track, and a trace plot; only that
# trial's event log and object track are kept.
fig = s.get("figures", {})
if set(fig) != ({"success"} if s["successes"] == 2 else set(fig)):
    fail.append(f"figures {sorted(fig)}, expected ['success']")
fail += missing_figure_files(out, fig)
for label, f in fig.items():
    if f.get("strip") and open(os.path.join(out, f["strip"]), "rb").read(8) != b"\x89PNG\r\n\x1a\n":
        fail.append(f"figures.{label}.strip is not a PNG")
kept = sorted(n for n in os.listdir(out) if n.endswith(".lcmlog"))
if kept != sorted(f["log"] for f in fig.values()):
    fail.append(f"event logs kept: {kept}, expected only the figures' trials")
if abs(starts[0] - starts[1]) < 1e-3:
    fail.append("both trials drew the same towel place")
print("\n".join("FAIL: " + f for f in fail) if fail else
      f"pmg_teleop_bench: 2 trials judged consistently with their trajectories ({s['successes']} successes)")
sys.exit(1 if fail else 0)
PY
# shellcheck source=bench_refuses.sh
. "$(dirname "${BASH_SOURCE[0]}")/bench_refuses.sh"
expect_refused "$bin" wipe "$d" bad 'view_noise_m: 0.005\nwalk_speed: 1\n' bad.yaml walk_speed
# A value out of its range is refused naming the file, the field and the range (the raised hand
# walks in only within raise_margin_m of hover_m + clearance_m).
expect_refused "$bin" wipe "$d" range 'hover_m: 0.06\nclearance_m: 0.12\nraise_margin_m: 0.5\n' range.yaml \
  'raise_margin_m: expected \[0, hover_m + clearance_m\]'
