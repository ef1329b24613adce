#!/usr/bin/env python3
"""Bar chart of the runs with a fall, per configuration, from pmg_policy_sil summaries.

Usage: scripts/plot_falls_by_config.py OUT.png LABEL=SUMMARY[,SUMMARY...] [LABEL=...] [--title T]

Each LABEL names one configuration; its SUMMARY files (summary.json of pmg_policy_sil runs, shell globs
allowed) are pooled. A run counts as fallen when its `falls_s` list is not empty (with
--restart-after-fall a run may fall more than once; it counts once). Each bar is annotated with
"k of n"; the table names the segments the falls happened in (the last segment whose `t_begin`
precedes the fall time).
Prints the same table to stdout. Exit status 2 on a summary without `runs`.
"""
import glob
import json
import sys


def count(paths):
    runs = 0
    fell = 0
    where = {}
    for p in paths:
        with open(p) as f:
            s = json.load(f)
        if "runs" not in s:
            sys.stderr.write(f"{p}: no `runs` (not a pmg_policy_sil summary)\n")
            sys.exit(2)
        starts = sorted((seg["t_begin"], seg["name"]) for seg in s.get("segments", []) if "t_begin" in seg)
        for r in s["runs"]:
            runs += 1
            if not r.get("falls_s"):
                continue
            fell += 1
            for t in r["falls_s"]:
                name = "?"
                for t0, n in starts:
                    if t0 <= t:
                        name = n
                where[name] = where.get(name, 0) + 1
    return runs, fell, where


def main(argv):
    title = None
    if "--title" in argv:
        i = argv.index("--title")
        title = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        return 1
    out = argv[1]
    rows = []
    for spec in argv[2:]:
        label, _, files = spec.partition("=")
        paths = []
        for pat in files.split(","):
            hit = sorted(glob.glob(pat))
            if not hit:
                sys.stderr.write(f"{label}: no file matches {pat}\n")
                return 1
            paths += hit
        runs, fell, where = count(paths)
        rows.append((label, runs, fell, where))
        segs = ", ".join(f"{k} {v}" for k, v in sorted(where.items(), key=lambda kv: (-kv[1], kv[0]))) or "-"
        print(f"{label}: {fell} of {runs} runs with a fall ({segs})")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(1.9 * len(rows) + 2, 3.8))
    xs = range(len(rows))
    ax.bar(xs, [r[2] for r in rows], color="tab:red", alpha=0.8)
    for x, (label, runs, fell, where) in zip(xs, rows):
        ax.annotate(f"{fell} of {runs}", (x, fell), ha="center", va="bottom", fontsize=9)
    ax.set_xticks(list(xs))
    ax.set_xticklabels([r[0] for r in rows], fontsize=8)
    ax.set_ylabel("runs with a fall")
    ax.set_ylim(0, max(1, max(r[2] for r in rows)) * 1.25)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
