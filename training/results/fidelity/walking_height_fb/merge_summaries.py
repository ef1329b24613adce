#!/usr/bin/env python3
"""Merge pmg_policy_sil summaries of the same command file run on disjoint seed ranges into one
(segment means weighted by the seeds that reached each segment's window; `fallen` summed; `runs` concatenated), so that
scripts/segment_band.py scores them as one battery. Usage: merge_summaries.py OUT.json IN.json IN.json ..."""
import json
import sys


def merge(values, weights):
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return sum(v * w for v, w in zip(values, weights)) / sum(weights)
    if all(isinstance(v, dict) for v in values):
        return {k: merge([v.get(k) for v in values], weights) for k in values[0]}
    if any(v is None for v in values):
        kept = [(v, w) for v, w in zip(values, weights) if v is not None]
        return merge([v for v, _ in kept], [w for _, w in kept]) if kept else None
    return values[0]


ins = [json.load(open(p)) for p in sys.argv[2:]]
w = [len(s["runs"]) for s in ins]
out = dict(ins[0])
out["runs"] = [r for s in ins for r in s["runs"]]
out["segments"] = []
for segs in zip(*[s["segments"] for s in ins]):
    assert len({x["name"] for x in segs}) == 1, "the summaries must come from the same command file"
    ws = [x["seeds"] if isinstance(x.get("seeds"), int) else wi for x, wi in zip(segs, w)]
    m = merge(list(segs), ws) if sum(ws) > 0 else dict(segs[0])
    m["fallen"] = sum(x.get("fallen", 0) for x in segs)
    m["seeds"] = sum(x.get("seeds", 0) for x in segs) if isinstance(segs[0].get("seeds"), int) else segs[0].get("seeds")
    out["segments"].append(m)
json.dump(out, open(sys.argv[1], "w"), indent=1)
