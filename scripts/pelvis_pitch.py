#!/usr/bin/env python3
"""Per segment of a pmg_policy_sil run: the achieved torso pitch, the pelvis pitch and their
difference (what the waist adds), seed means over each segment's last 60 %.

Usage: scripts/pelvis_pitch.py OUT_DIR [--segments a,b,...]

OUT_DIR is a `pmg_policy_sil --out` folder: seed<k>.csv (per tick: `segment`, achieved torso_link
`pitch` [rad]) and frames<k>.csv (body positions in the world frame W every --frame-period).
The pelvis attitude comes from the frames: the hip pitch links sit at (0, ±0.064452, −0.1027) m
in the pelvis frame B (G1 MJCF), so the pelvis z axis is (p_pelvis − midpoint of the two hip
links) / |.| and its lateral axis is along left hip − right hip. Pelvis pitch = the tilt of that z
axis towards the pelvis heading, forward (nose down) positive, as the torso pitch.
Why: the PD-driven waist follows the reference's waist lean (docs/policy.md "Reference torso
pitch"); with the torso upright the pelvis must tilt back by that lean. This measures it.
"""
import argparse
import csv
import glob
import math
import os
import sys


def _vec(text):
    return [float(x) for x in text.split()]


def _pelvis_pitch(pelvis, hip_l, hip_r):
    mid = [(a + b) / 2 for a, b in zip(hip_l, hip_r)]
    z = [p - m for p, m in zip(pelvis, mid)]
    y = [a - b for a, b in zip(hip_l, hip_r)]
    # Heading: horizontal direction perpendicular to the hip axis (x = y × z_world, normalised).
    hx, hy = y[1], -y[0]
    n = math.hypot(hx, hy)
    if n == 0:
        return float("nan")
    hx, hy = hx / n, hy / n
    return math.atan2(z[0] * hx + z[1] * hy, z[2])


def seed_rows(out_dir, k):
    """(t, segment, torso pitch) per tick, and {t: pelvis pitch} per frame, of seed k."""
    with open(os.path.join(out_dir, f"seed{k}.csv")) as f:
        r = csv.reader(f)
        head = next(r)
        it, iseg, ip = head.index("t"), head.index("segment"), head.index("pitch")
        ticks = [(float(x[it]), x[iseg], float(x[ip])) for x in r]
    frames = {}
    with open(os.path.join(out_dir, f"frames{k}.csv")) as f:
        r = csv.reader(f)
        head = [h.split(":")[0] for h in next(r)]
        ip, il, ir = head.index("pelvis"), head.index("left_hip_pitch_link"), head.index("right_hip_pitch_link")
        for x in r:
            frames[round(float(x[0]), 6)] = _pelvis_pitch(_vec(x[ip]), _vec(x[il]), _vec(x[ir]))
    return ticks, frames


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("--segments", default="", help="comma-separated segment names (default: all)")
    args = ap.parse_args()
    seeds = sorted(int(os.path.basename(p)[4:-4]) for p in glob.glob(os.path.join(args.out_dir, "seed*.csv")))
    if not seeds:
        sys.exit(f"{args.out_dir}: no seed<k>.csv (a pmg_policy_sil --out folder)")
    per_seg = {}  # name -> list of (torso, pelvis) seed means
    order = []
    for k in seeds:
        ticks, frames = seed_rows(args.out_dir, k)
        spans = {}
        for t, seg, _ in ticks:
            if seg not in spans:
                spans[seg] = [t, t]
                if seg not in order:
                    order.append(seg)
            spans[seg][1] = t
        for seg, (t0, t1) in spans.items():
            w0 = t0 + 0.4 * (t1 - t0)
            torso = [p for t, s, p in ticks if s == seg and t >= w0]
            pelvis = [v for t, v in frames.items() if w0 <= t <= t1 and not math.isnan(v)]
            if torso and pelvis:
                per_seg.setdefault(seg, []).append((sum(torso) / len(torso), sum(pelvis) / len(pelvis)))
    wanted = [s for s in args.segments.split(",") if s] or order
    print(f"{args.out_dir}: {len(seeds)} seed(s); means over the last 60 % of each segment [rad]")
    print(f"{'segment':16s} {'torso':>8s} {'pelvis':>8s} {'waist':>8s}")
    for seg in wanted:
        v = per_seg.get(seg)
        if not v:
            continue
        torso = sum(a for a, _ in v) / len(v)
        pelvis = sum(b for _, b in v) / len(v)
        print(f"{seg:16s} {torso:+8.3f} {pelvis:+8.3f} {torso - pelvis:+8.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
