#!/usr/bin/env python3
"""Is the actor mirror-symmetric? Run a command script and its mirror image, compare side by side.

The G1 and its references are (nearly) symmetric about the sagittal plane, so a command and its mirror
image (v_y, omega and roll negated) should be carried equally well. This tool
  1. writes the mirror image of a pmg_policy_sil command script (`mirror IN OUT`), and
  2. compares the two runs' summary.json per segment (`compare ORIG MIRRORED [--out PNG]`): for every
     segment that commands v_y or omega, achieved / commanded on each side, and the difference;
     prints the table, draws it, and names the segments whose two sides differ by more than the
     issue's band (15 % of the command).

  python3 scripts/mirror_grid.py mirror config/policies/eval_envelope.yaml /tmp/mirrored.yaml
  build/bin/pmg_policy_sil --commands config/policies/eval_envelope.yaml --seeds 6 --restart-after-fall --out A
  build/bin/pmg_policy_sil --commands /tmp/mirrored.yaml --seeds 6 --restart-after-fall --out B
  python3 scripts/mirror_grid.py compare A/summary.json B/summary.json --out mirror.png
"""
import argparse
import json
import sys

import yaml

MIRRORED_KEYS = ("vy", "wz", "roll")  # heading frame: v_y, yaw rate and roll change sign in the mirror


def mirror_script(src, dst):
    with open(src) as f:
        doc = yaml.safe_load(f)
    segments = doc.get("segments") if isinstance(doc, dict) else None
    if not isinstance(segments, list) or not segments:
        raise SystemExit(f"{src}: field 'segments': expected a non-empty list of segments")
    for i, seg in enumerate(segments):
        for k in MIRRORED_KEYS:
            if k in seg:
                if not isinstance(seg[k], (int, float)):
                    raise SystemExit(f"{src}: segments[{i}].{k} = {seg[k]!r}: expected a number")
                seg[k] = -seg[k] if seg[k] else 0
    with open(dst, "w") as f:
        f.write(f"# The mirror image of {src} (v_y, wz and roll negated), written by\n"
                f"#   python3 scripts/mirror_grid.py mirror {src} {dst}\n")
        yaml.safe_dump(doc, f, sort_keys=False, default_flow_style=None)


def ratio(seg, k):
    c, a = seg["command"][k], (seg.get("achieved") or {}).get(k)
    return None if not c or a is None else a / c


def compare(orig_path, mirrored_path, out):
    with open(orig_path) as f:
        a = json.load(f)["segments"]
    with open(mirrored_path) as f:
        b = json.load(f)["segments"]
    if [s["name"] for s in a] != [s["name"] for s in b]:
        raise SystemExit(f"{orig_path} and {mirrored_path}: different segments; expected a script and its mirror")
    rows = []
    for x, y in zip(a, b):
        for k in ("vy", "wz"):
            if not x["command"][k]:
                continue
            if abs(y["command"][k] + x["command"][k]) > 1e-9:
                raise SystemExit(f"segment {x['name']}: {k} {x['command'][k]} and {y['command'][k]}: not mirror images")
            rows.append((x["name"], k, ratio(x, k), ratio(y, k)))
    print(f"{'segment':14} {'axis':4} {'original':>9} {'mirrored':>9} {'difference':>10}")
    differ = []
    for name, k, r0, r1 in rows:
        d = None if r0 is None or r1 is None else r1 - r0
        print(f"{name:14} {k:4} {'-' if r0 is None else f'{r0:9.2f}':>9} {'-' if r1 is None else f'{r1:9.2f}':>9} "
              f"{'-' if d is None else f'{d:+10.2f}':>10}")
        if d is not None and abs(d) > 0.15:
            differ.append(f"{name} {k} ({r0:.2f} / {r1:.2f})")
    print(f"sides differ by more than 15 % of the command: {len(differ)} of {len(rows)}"
          + (": " + ", ".join(differ) if differ else ""))
    if out:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(max(8, 0.55 * len(rows)), 4.2))
        xs = range(len(rows))
        ax.bar([i - 0.2 for i in xs], [r[2] or 0 for r in rows], 0.4, label="original")
        ax.bar([i + 0.2 for i in xs], [r[3] or 0 for r in rows], 0.4, label="mirror image")
        ax.axhspan(0.85, 1.15, color="g", alpha=0.12, label="±15 % of the command")
        ax.set_xticks(list(xs))
        ax.set_xticklabels([f"{r[0]} {'v_y' if r[1] == 'vy' else 'ω'}" for r in rows], fontsize=8, rotation=40,
                           ha="right")
        ax.set_ylabel("achieved / commanded")
        ax.set_title("each segment and its mirror image (v_y, ω negated): SIL, product path")
        ax.legend(fontsize=8)
        ax.grid(axis="y", alpha=0.3)
        fig.tight_layout()
        fig.savefig(out, dpi=110)
        print("wrote", out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("mirror")
    m.add_argument("src")
    m.add_argument("dst")
    c = sub.add_parser("compare")
    c.add_argument("orig")
    c.add_argument("mirrored")
    c.add_argument("--out")
    args = ap.parse_args(argv)
    if args.cmd == "mirror":
        mirror_script(args.src, args.dst)
    else:
        compare(args.orig, args.mirrored, args.out)


if __name__ == "__main__":
    sys.exit(main())
