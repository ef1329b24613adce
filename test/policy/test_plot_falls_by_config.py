#!/usr/bin/env python3
"""Tests scripts/plot_falls_by_config.py on synthetic pmg_policy_sil summaries (ctest
plot_falls_by_config_counts_known_falls, label unit). Configuration A: two summaries of 3 and 2 runs; one run
fell twice (at 5.5 s in `arc`, which begins at 4 s, and at 9 s in `stop`, from 8 s), one fell once at 1 s (in
`stand`); configuration B: one summary, no fall:
- the table says "A: 2 of 5 runs with a fall (arc 1, stand 1, stop 1)" (a run counts once, each fall by its
  segment) and "B: 0 of 2 runs with a fall (-)"; the PNG is written;
- a summary without `runs` exits with status 2, naming the file; a pattern matching nothing is refused.
Usage: test_plot_falls_by_config.py
"""
import contextlib
import io
import json
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import plot_falls_by_config as pf  # noqa: E402
from script_checks import Checks  # noqa: E402  (beside this file)

check = Checks()
SEGMENTS = [{"name": "stand", "t_begin": 0.0}, {"name": "arc", "t_begin": 4.0}, {"name": "stop", "t_begin": 8.0}]


def write(path, falls):
    with open(path, "w") as f:
        json.dump({"segments": SEGMENTS, "runs": [{"seed": k, "falls_s": fs} for k, fs in enumerate(falls)]}, f)


def main():
    with tempfile.TemporaryDirectory() as tmp:
        write(os.path.join(tmp, "a1.json"), [[], [5.5, 9.0], []])
        write(os.path.join(tmp, "a2.json"), [[1.0], []])
        write(os.path.join(tmp, "b.json"), [[], []])
        png = os.path.join(tmp, "out.png")
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            rc = pf.main(["x", png, f"A={tmp}/a*.json", f"B={tmp}/b.json", "--title", "t"])
        text = out.getvalue()
        check(rc == 0, "exit status 0")
        check("A: 2 of 5 runs with a fall (arc 1, stand 1, stop 1)" in text, f"configuration A counted: {text!r}")
        check("B: 0 of 2 runs with a fall (-)" in text, "configuration B: no fall")
        check(os.path.getsize(png) > 1000, "the PNG is written")
        with open(os.path.join(tmp, "bad.json"), "w") as f:
            json.dump({"segments": []}, f)
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                pf.main(["x", png, f"C={tmp}/bad.json"])
            code = 0
        except SystemExit as e:
            code = e.code
        check(code == 2 and "bad.json: no `runs`" in err.getvalue(), "a summary without runs: status 2, naming it")
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            rc = pf.main(["x", png, f"D={tmp}/none*.json"])
        check(rc == 1 and "D: no file matches" in err.getvalue(), "a pattern matching nothing is refused")
    return check.exit_code()


if __name__ == "__main__":
    sys.exit(main())
