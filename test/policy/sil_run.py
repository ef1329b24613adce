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


def last60(rs, name):
    """Rows of segment NAME in the last 60 % of it (the window of the summary's segment means)."""
    seg_rows = [r for r in rs if r["segment"] == name]
    length = seg_rows[-1]["t"] - seg_rows[0]["t"]
    return window(rs, name, 0.4 * length, length + 1.0)


def stop_speed(rs, name, t0=1.0, t1=3.0):
    """Mean v_x [m/s] over [t0, t1) s into segment NAME (1-3 s into a stop: did the robot stop when told?)."""
    w = window(rs, name, t0, t1)
    return sum(r["vx"] for r in w) / len(w)


def seg(summary, name):
    """The summary's pooled segment NAME (summary.json "segments")."""
    return next(x for x in summary["segments"] if x["name"] == name)


def still_after(rs, t_stop, limit=0.15, span=0.5):
    """Seconds from t_stop until the 0.5 s mean of |v_x| first falls below limit (None: never)."""
    after = [r for r in rs if r["t"] >= t_stop]
    n = int(round(span / 0.01))
    for i in range(len(after) - n):
        if abs(sum(r["vx"] for r in after[i:i + n]) / n) < limit:
            return after[i]["t"] - t_stop
    return None


def report(checks):
    """Prints each named check as ok/FAIL; 0 when all hold, else 1 (the check scripts' exit status)."""
    for name, ok in checks.items():
        print(("ok   " if ok else "FAIL ") + name)
    return 0 if all(checks.values()) else 1


def run_off_on(checks, seed, argv):
    """An off/on SIL check's main: argv = [script, OFF_DIR, ON_DIR]; checks(s_off, r_off, s_on, r_on)
    (rows() of SEED in each) prints its measures and returns {name: ok}. Returns report()'s status."""
    if len(argv) != 3:
        print(f"usage: {argv[0]} OFF_DIR ON_DIR")
        return 2
    return report(checks(*rows(argv[1], seed), *rows(argv[2], seed)))
