#!/usr/bin/env python3
"""Checks the SIL's foot-floor friction through the product path (ctest pmg_policy_sil_sliding_friction,
label sil): the default config walks test/data/policy/eval_bent_walk.yaml (0.3 m/s bent 0.25 rad) on seeds
0-1, once on the MJCF's floor and once with pmg_policy_sil --sliding-friction 0.2 (docs/controller.md
"Slippery floors"). The hidden effect, from each run's summary.json:
- the summary records the friction simulated: 1.0 (the MJCF's) and 0.2;
- on the slippery floor every seed's feet slide faster while touching the floor (foot_slip), and the mean
  by at least 15 % (measured on 0.3 with the default of 2026-12-01: 0.081 -> 0.108 m/s; F13, the default's actor
  since 2026-12-07, slides little on the MJCF's floor, and on 0.3 its feet slid only 15-16 % faster (0.109 -> 0.127,
  and 0.107 -> 0.123 with the walking posture loop damped), too near the line; on 0.2: 0.107 -> 0.147 m/s);
- no fall on either floor.
Usage: check_sil_sliding_friction.py NOMINAL_DIR SLIPPERY_DIR
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import run_off_on  # noqa: E402


def checks(a, _rows_a, b, _rows_b):
    """The claims on the nominal (a) and slippery (b) summaries."""
    slip_a = {r["seed"]: r["foot_slip"] for r in a["runs"]}
    slip_b = {r["seed"]: r["foot_slip"] for r in b["runs"]}
    mean_a, mean_b = sum(slip_a.values()) / len(slip_a), sum(slip_b.values()) / len(slip_b)
    print(f"floor friction {a['floor_friction']} / {b['floor_friction']}; foot slip per seed {slip_a} / {slip_b}; "
          f"mean {mean_a:.4f} / {mean_b:.4f} m/s; falls {a['mean']['falls']} / {b['mean']['falls']}")
    same_seeds = sorted(slip_a) == sorted(slip_b) and len(slip_a) >= 2
    return {
        "the summaries record the frictions simulated (1.0 and 0.2)":
            abs(a["floor_friction"] - 1.0) < 1e-9 and abs(b["floor_friction"] - 0.2) < 1e-9,
        "the same two or more seeds in both runs": same_seeds,
        "every seed's feet slide faster on the slippery floor": same_seeds and all(slip_b[k] > slip_a[k] for k in slip_a),
        "the mean foot slip 15 % or more above the nominal floor's": mean_b > 1.15 * mean_a,
        "no fall": not a["mean"]["falls"] and not b["mean"]["falls"],
    }


if __name__ == "__main__":
    sys.exit(run_off_on(checks, 0, sys.argv))
