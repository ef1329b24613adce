#!/usr/bin/env python3
"""How symmetric is the reference the policy is told to stand in? Per standing segment of a pmg_policy_sil run
(every velocity command zero), at the segment's last tick, the leg reference's hip yaw and hip roll (the larger
magnitude of the two legs) and the left-right difference of the knees, in rad, over the seeds of OUT_DIR.

The generator's own standing templates are symmetric (all three near 0 with `stride_adaptation` off); the stride
adaptation's `standing_hold` keeps the feet where the last steps put them, toe-out and split stance included, until
the next walk (docs/gco.md "Stride adaptation"), so what this prints is how far from the templates the robot is made
to stand, crouch and bend.

Columns read from seedN.csv: t, segment, vx_cmd, vy_cmd, wz_cmd and qref0..qref11, the legs in the G1's joint order
(left then right: hip pitch, hip roll, hip yaw, knee, ankle pitch, ankle roll; config/robots/g1/g1.yaml).
Segments whose name starts with "restart" (--restart-after-fall's) are skipped.

  python3 scripts/standing_reference.py OUT_DIR [--json FILE]
Exit status 2 (with a message naming it) when OUT_DIR has no seedN.csv or a file lacks a column.
"""
import argparse
import csv
import glob
import json
import os
import re
import sys

HIP_ROLL, HIP_YAW, KNEE = 1, 2, 3  # within one leg's six joints
LEG = 6


def standing_ends(path):
    """{segment: (hip yaw, hip roll, |knee L-R|)} at the last tick of each standing segment of one seed's CSV."""
    last = {}
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        need = ["t", "segment", "vx_cmd", "vy_cmd", "wz_cmd"] + [f"qref{i}" for i in range(2 * LEG)]
        missing = [c for c in need if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: no column {', '.join(missing)} (expected pmg_policy_sil's seedN.csv)")
        for row in reader:
            if row["segment"].startswith("restart"):
                continue
            last[row["segment"]] = row
    out = {}
    for seg, row in last.items():
        if any(float(row[k]) != 0.0 for k in ("vx_cmd", "vy_cmd", "wz_cmd")):
            continue
        q = [float(row[f"qref{i}"]) for i in range(2 * LEG)]
        out[seg] = (max(abs(q[HIP_YAW]), abs(q[LEG + HIP_YAW])),
                    max(abs(q[HIP_ROLL]), abs(q[LEG + HIP_ROLL])),
                    abs(q[KNEE] - q[LEG + KNEE]))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--json", help="also write the table here")
    a = ap.parse_args(argv)
    files = sorted(glob.glob(os.path.join(a.out_dir, "seed*.csv")),
                   key=lambda p: int(re.sub(r"\D", "", os.path.basename(p)) or 0))
    if not files:
        print(f"standing_reference: no seedN.csv in {a.out_dir}", file=sys.stderr)
        return 2
    per_seg = {}
    try:
        for p in files:
            for seg, v in standing_ends(p).items():
                per_seg.setdefault(seg, []).append(v)
    except ValueError as e:
        print(f"standing_reference: {e}", file=sys.stderr)
        return 2
    table = []
    print(f"standing segments of {a.out_dir} ({len(files)} seeds), the leg reference at each segment's end [rad]:")
    print(f"{'segment':<18} {'seeds':>5} {'hip yaw max':>12} {'mean':>7} {'hip roll max':>13} {'mean':>7} {'|knee L-R| max':>15} {'mean':>7}")
    for seg, vals in per_seg.items():
        n = len(vals)
        row = {"segment": seg, "seeds": n}
        cells = []
        for i, key in enumerate(("hip_yaw", "hip_roll", "knee_difference")):
            mx = max(v[i] for v in vals)
            mean = sum(v[i] for v in vals) / n
            row[key] = {"max": mx, "mean": mean}
            cells.append(f"{mx:>{12 + (i > 0) + 2 * (i > 1)}.3f} {mean:>7.3f}")
        table.append(row)
        print(f"{seg:<18} {n:>5} " + " ".join(cells))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"out_dir": a.out_dir, "seeds": len(files), "segments": table}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
