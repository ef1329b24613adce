#!/usr/bin/env bash
# pmg_teleop_bench --task box (issue 14) runs 2 randomised box trials end to end (scene drawn,
# ControllerApp in lockstep, the scripted two-handed operator through the VR stream, the box judged)
# and reports truthfully: summary.json has the issue's keys, every failure carries one of the judge's
# classes, each verdict agrees with the box trajectory in the trial's CSV (largest lift of the bottom
# above the pick top, horizontal carry, end on the place top), the two trials drew different box
# poses, and the first failure's figures exist. It does NOT assert success: the box operator does not
# carry the box yet (docs/teleop.md reports the 20-trial rate and why); issue 14 stays open on it.
#   teleop_bench_box_test.sh BIN_DIR
set -euo pipefail
bin="${1:?usage: teleop_bench_box_test.sh BIN_DIR}"
d="$(mktemp -d)"
trap 'rm -rf "$d"' EXIT
"$bin/pmg_teleop_bench" --task box --trials 2 --seed 0 --out "$d/out" > "$d/log.txt"
cat "$d/log.txt"
python3 - "$d/out" <<'PY'
import csv, json, math, os, sys
out = sys.argv[1]
s = json.load(open(os.path.join(out, "summary.json")))
fail = []
for k in ("task", "trials", "successes", "success_rate", "failures", "paper_success_rate"):
    if k not in s:
        fail.append(f"summary.json lacks {k}")
if s["task"] != "box" or s["paper_success_rate"] != 0.8:
    fail.append(f"task {s['task']}, paper rate {s['paper_success_rate']}")
if s["trials"] != 2 or len(s["trial_results"]) != 2 or s["successes"] + len(s["failures"]) != 2:
    fail.append(f"trial counts: {s['trials']}, {len(s['trial_results'])}, {s['successes']} + {len(s['failures'])}")
known = {"loss_of_balance", "dropped", "not_lifted", "not_carried", "tipped", "not_placed"}
for f in s["failures"]:
    if f["reason"] not in known:
        fail.append(f"unknown failure class {f['reason']}")
# config/tasks/box_scene.yaml: pick top 0.50 m, place top 0.76 m; the box is 0.20 m tall.
half, pick_top, place_top = 0.10, 0.50, 0.76
starts = []
for r in s["trial_results"]:
    rows = list(csv.DictReader(open(os.path.join(out, f"trial_{r['trial']}.csv"))))
    x = [float(q["obj_x"]) for q in rows]
    y = [float(q["obj_y"]) for q in rows]
    z = [float(q["obj_z"]) for q in rows]
    starts.append((x[0], y[0]))
    lift = max(zz - half for zz in z) - pick_top
    if abs(lift - r["measure"]) > 0.002:
        fail.append(f"trial {r['trial']}: judged lift {r['measure']:.4f} m, CSV lift {lift:.4f} m")
    carry = math.hypot(x[-1] - x[0], y[-1] - y[0])
    on_place = abs(z[-1] - half - place_top) < 0.01
    if r["success"] and not (lift >= 0.28 and carry >= 0.45 and on_place and not r["fell"]):
        fail.append(f"trial {r['trial']}: judged a success, CSV lift {lift:.3f}, carry {carry:.3f}, on the place top {on_place}")
if abs(starts[0][0] - starts[1][0]) + abs(starts[0][1] - starts[1][1]) < 1e-3:
    fail.append("both trials drew the same box place")
fig = s.get("figures", {})
for label, f in fig.items():
    for key in ("log", "objects", "scene", "strip", "trace"):
        p = f.get(key)
        if not p or not os.path.isfile(os.path.join(out, p)) or os.path.getsize(os.path.join(out, p)) < 1000:
            fail.append(f"figures.{label}.{key} = {p}: missing or empty")
if not fig:
    fail.append("no figures")
print("\n".join("FAIL: " + f for f in fail) if fail else
      f"pmg_teleop_bench --task box: 2 trials judged consistently with their trajectories ({s['successes']} successes)")
sys.exit(1 if fail else 0)
PY
printf 'view_noise_m: 0.005\nsqueeze_force: 1\n' > "$d/bad.yaml"
if "$bin/pmg_teleop_bench" --task box --trials 1 --operator "$d/bad.yaml" --out "$d/bad" > "$d/bad.txt" 2>&1; then
  echo "FAIL: a bad box operator file was accepted"; exit 1
fi
grep -q "bad.yaml" "$d/bad.txt" && grep -q "squeeze_force" "$d/bad.txt" || { cat "$d/bad.txt"; exit 1; }
