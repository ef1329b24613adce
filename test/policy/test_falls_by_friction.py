#!/usr/bin/env python3
"""Tests training/falls_by_friction.py on a synthetic segment_robots.py summary (ctest
falls_by_friction_counts_a_known_summary, label unit). Six robots drew friction 0.45, 0.5, 0.7, 0.9, 1.0 and
1.25; robots 0, 1 and 5 fell (segment_robots.py's fallen_by_end: robot 0 in the first segment, 1 and 5 in the
last):
- the default bins give fallen / robots 2/2, 0/1, 0/1, 1/2 (1.0 opens the last bin, 1.25 closes it);
- other edges regroup them (0.4, 0.8, 1.25: 2/3 and 1/3); a friction outside the bins and edges that do not
  increase are refused, naming them.
Usage: test_falls_by_friction.py
"""
import contextlib
import io
import json
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "training"))
import falls_by_friction as fbf  # noqa: E402
from script_checks import Checks  # noqa: E402  (beside this file)

check = Checks()


def main():
    down = [True, True, False, False, False, True]
    summary = {"stand": {"command_vx": 0.0, "vx": [None, 0.0, 0.0, 0.0, 0.0, 0.0], "fallen_by_end": [True] + [False] * 5},
               "walk": {"command_vx": 0.3, "vx": [None, None, 0.3, 0.3, 0.3, None], "fallen_by_end": down},
               "drawn_friction": [0.45, 0.5, 0.7, 0.9, 1.0, 1.25], "drawn_mass": [33.0] * 6}
    robots, fallen = fbf.fallen_by_bin(summary, [0.4, 0.6, 0.8, 1.0, 1.25])
    check(robots == [2, 1, 1, 2] and fallen == [2, 0, 0, 1], f"default bins: fallen {fallen} of {robots}")
    robots, fallen = fbf.fallen_by_bin(summary, [0.4, 0.8, 1.25])
    check(robots == [3, 3] and fallen == [2, 1], f"bins 0.4, 0.8, 1.25: fallen {fallen} of {robots}")
    try:
        fbf.fallen_by_bin(summary, [0.5, 1.0])
        msg = ""
    except ValueError as e:
        msg = str(e)
    check("robot 0: friction 0.45 outside the bins" in msg, f"a friction outside the bins is refused: {msg}")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "s.json")
        with open(path, "w") as f:
            json.dump(summary, f)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            rc = fbf.main([path])
        check(rc == 0 and f"{path}: 3 of 6; 2/2 (1.00), 0/1 (0.00), 0/1 (0.00), 1/2 (0.50)" in out.getvalue(),
              "the printed row: 3 of 6, by bin")
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                fbf.main([path, "--bins", "1.0,0.5"])
            code = 0
        except SystemExit as e:
            code = e.code
        check(code == 2 and "--bins 1.0,0.5" in err.getvalue(), "edges that do not increase are refused")
    return check.exit_code()


if __name__ == "__main__":
    sys.exit(main())
