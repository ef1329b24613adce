"""Reading a pmg_policy_sil output directory in the SIL checks (test/policy/check_sil_*.py)."""
import csv
import json


def rows(out, seed=0):
    """(summary.json, the per-tick rows of seed<seed>.csv with every column but segment and mode as float)."""
    with open(f"{out}/summary.json") as f:
        s = json.load(f)
    with open(f"{out}/seed{seed}.csv") as f:
        return s, [{k: (v if k in ("segment", "mode") else float(v)) for k, v in r.items()} for r in csv.DictReader(f)]


def window(rs, name, t0, t1):
    """Rows of segment NAME whose time since the segment's first row lies in [t0, t1) s."""
    seg = [r for r in rs if r["segment"] == name]
    start = seg[0]["t"]
    return [r for r in seg if t0 <= r["t"] - start < t1]
