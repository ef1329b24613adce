#!/usr/bin/env python3
"""Pools several pmg_policy_sil summaries of the same command script into one.

Usage: scripts/pool_summaries.py OUT.json SUMMARY.json [SUMMARY.json ...]

Each summary's `segments` hold per-segment means over its seeds (`seeds` of them). The pooled
segment's `achieved` and `reference` values are the seed-weighted means of the inputs', `seeds` their
sum, and `fallen` the sum of the inputs'. The per-seed `runs` and the sequence `mean` are dropped (they
are not pooled); `pooled_from` lists the inputs. The segments must match by name and command, else
exit status 2 naming the file and the segment. Score the result with scripts/segment_band.py.
"""
import json
import sys


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    out, paths = argv[1], argv[2:]
    summaries = []
    for p in paths:
        with open(p) as f:
            s = json.load(f)
        if "segments" not in s:
            print(f"{p}: no 'segments' (expected pmg_policy_sil's summary.json)", file=sys.stderr)
            return 2
        summaries.append(s)
    base = json.loads(json.dumps(summaries[0]))
    for p, s in zip(paths[1:], summaries[1:]):
        if [(g["name"], g["command"]) for g in s["segments"]] != [(g["name"], g["command"]) for g in base["segments"]]:
            print(f"{p}: its segments (names, commands) differ from {paths[0]}'s", file=sys.stderr)
            return 2
    for i, seg in enumerate(base["segments"]):
        parts = [s["segments"][i] for s in summaries]
        seg["seeds"] = sum(g.get("seeds", 0) for g in parts)
        seg["fallen"] = sum(g.get("fallen", 0) for g in parts)
        for key in ("achieved", "reference"):
            if not seg.get(key):
                continue
            for axis in seg[key]:
                vals = [(g[key][axis], g.get("seeds", 0)) for g in parts
                        if g.get(key) and g[key].get(axis) is not None]
                weight = sum(w for _, w in vals)
                if vals and weight > 0:
                    seg[key][axis] = sum(v * w for v, w in vals) / weight
    base.pop("runs", None)
    base.pop("mean", None)
    base["pooled_from"] = paths
    with open(out, "w") as f:
        json.dump(base, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
