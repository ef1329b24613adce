#!/usr/bin/env python3
"""Checks the SIL's foot-floor friction through the product path (ctest pmg_policy_sil_sliding_friction,
label sil): the default config walks test/data/policy/eval_bent_walk.yaml (0.3 m/s bent 0.25 rad) on seeds
0-1, once on the MJCF's floor and once with pmg_policy_sil --sliding-friction 0.3 (docs/controller.md
"Slippery floors"). The hidden effect, from each run's summary.json:
- the summary records the friction simulated: 1.0 (the MJCF's) and 0.3;
- on the slippery floor every seed's feet slide faster while touching the floor (foot_slip), and the mean
  by at least 15 % (measured 0.081 -> 0.108 m/s);
- no fall on either floor.
Usage: check_sil_sliding_friction.py NOMINAL_DIR SLIPPERY_DIR
"""
import json
import os
import sys


def summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)


def main(nominal_dir, slippery_dir):
    a, b = summary(nominal_dir), summary(slippery_dir)
    slip_a = {r["seed"]: r["foot_slip"] for r in a["runs"]}
    slip_b = {r["seed"]: r["foot_slip"] for r in b["runs"]}
    mean_a, mean_b = sum(slip_a.values()) / len(slip_a), sum(slip_b.values()) / len(slip_b)
    print(f"floor friction {a['floor_friction']} / {b['floor_friction']}; foot slip per seed {slip_a} / {slip_b}; "
          f"mean {mean_a:.4f} / {mean_b:.4f} m/s; falls {a['mean']['falls']} / {b['mean']['falls']}")
    failures = []
    if not (abs(a["floor_friction"] - 1.0) < 1e-9 and abs(b["floor_friction"] - 0.3) < 1e-9):
        failures.append("the summaries do not record the frictions simulated (1.0 and 0.3)")
    if sorted(slip_a) != sorted(slip_b) or len(slip_a) < 2:
        failures.append(f"expected the same two or more seeds in both runs: {sorted(slip_a)} / {sorted(slip_b)}")
    elif not all(slip_b[s] > slip_a[s] for s in slip_a):
        failures.append("a seed's feet do not slide faster on the slippery floor")
    if not mean_b > 1.15 * mean_a:
        failures.append(f"mean foot slip {mean_b:.4f} is not 15 % above {mean_a:.4f}")
    if a["mean"]["falls"] or b["mean"]["falls"]:
        failures.append("a fall")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
