#!/usr/bin/env python3
"""Pelvis height in contact and in flight over a window of pmg_policy_sil per-tick CSVs
(training/results/fidelity/walking_height_fb/flight_height/README.md).

  python3 training/results/fidelity/walking_height_fb/flight_height/flight_height.py OUT T0 T1 [SEED ...]

OUT: a pmg_policy_sil --out folder (seedN.csv); T0..T1: the window [s]. Flight: neither foot in contact (the
simulator's contact_l/contact_r). Prints, per seed, the share of flight ticks and the mean pelvis height (truth,
height) over all ticks, in contact and in flight, and the mean height command sent to the actor (height_fb).
"""
import csv
import glob
import os
import sys


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    out, t0, t1 = argv[0], float(argv[1]), float(argv[2])
    seeds = argv[3:] or sorted(os.path.basename(p)[4:-4] for p in glob.glob(os.path.join(out, "seed*.csv")))
    for s in seeds:
        with open(os.path.join(out, f"seed{s}.csv")) as f:
            rows = [r for r in csv.DictReader(f) if t0 <= float(r["t"]) <= t1]
        if not rows:
            sys.exit(f"{out}/seed{s}.csv: no ticks in [{t0}, {t1}] s")
        flight, contact = [], []
        for r in rows:
            (flight if float(r["contact_l"]) < 0.5 and float(r["contact_r"]) < 0.5 else contact).append(r)

        def mean(sel, key="height"):
            return sum(float(r[key]) for r in sel) / len(sel) if sel else float("nan")
        print(f"seed {s}: flight {len(flight) / len(rows):.2f} of {len(rows)} ticks; pelvis height all {mean(rows):.4f}, "
              f"in contact {mean(contact):.4f}, in flight {mean(flight):.4f} m; height_fb {mean(rows, 'height_fb'):.4f} m")


if __name__ == "__main__":
    main(sys.argv[1:])
