#!/usr/bin/env python3
"""Tests scripts/mirror_grid.py (ctest mirror_grid_finds_a_one_sided_segment, label unit).

1. `mirror` negates v_y, wz and roll of every segment of a command script and keeps everything else
   (ramp, duration, names, times, v_x, pitch, height); mirroring twice gives the script back; a
   segment whose wz is not a number is refused, naming the file and the field.
2. `compare` on synthetic summaries of a script and its mirror image, with one segment carried
   one-sidedly (diag: v_y 60 % on the original side, 100 % on the mirrored one) and the others alike:
   it names exactly that segment's v_y, and refuses two summaries whose commands are not mirror images.
Usage: test_mirror_grid.py
"""
import json
import os
import subprocess
import sys
import tempfile

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOOL = os.path.join(ROOT, "scripts", "mirror_grid.py")
SCRIPT = {"ramp": 0.5, "duration": 12.0, "segments": [
    {"name": "stand", "t": 0, "vx": 0, "vy": 0, "wz": 0, "pitch": 0, "roll": 0, "height": 0.78},
    {"name": "diag", "t": 3, "vx": 0.5, "vy": 0.3, "wz": 0.5, "pitch": 0.1, "roll": 0.1, "height": 0.7},
    {"name": "turn", "t": 7, "vx": 0, "vy": 0, "wz": -0.4, "pitch": 0, "roll": 0, "height": 0.78}]}


def run(*args):
    return subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True)


def seg(name, command, achieved):
    return {"name": name, "command": command, "reference": command, "achieved": achieved}


def main():
    failures = []
    with tempfile.TemporaryDirectory() as d:
        src, dst, back = (os.path.join(d, n) for n in ("a.yaml", "b.yaml", "c.yaml"))
        with open(src, "w") as f:
            yaml.safe_dump(SCRIPT, f)
        r = run("mirror", src, dst)
        with open(dst) as f:
            m = yaml.safe_load(f)
        want = json.loads(json.dumps(SCRIPT))
        for s in want["segments"]:
            for k in ("vy", "wz", "roll"):
                s[k] = -s[k] if s[k] else 0
        if r.returncode != 0 or m != want:
            failures.append(f"mirror: rc {r.returncode}, got {m}, {r.stderr}")
        run("mirror", dst, back)
        with open(back) as f:
            if yaml.safe_load(f) != SCRIPT:
                failures.append("mirroring twice did not give the script back")
        bad = json.loads(json.dumps(SCRIPT))
        bad["segments"][2]["wz"] = "fast"
        with open(src, "w") as f:
            yaml.safe_dump(bad, f)
        r = run("mirror", src, dst)
        if r.returncode == 0 or "segments[2].wz" not in r.stderr or src not in r.stderr:
            failures.append(f"a non-numeric wz: rc {r.returncode}, message {r.stderr.strip()!r}")

        def summary(sign, diag_vy):
            c = {"vx": 0.5, "vy": 0.3 * sign, "wz": 0.5 * sign}
            t = {"vx": 0.0, "vy": 0.0, "wz": -0.4 * sign}
            return {"segments": [seg("diag", c, {"vx": 0.5, "vy": diag_vy * sign, "wz": 0.48 * sign}),
                                 seg("turn", t, {"vx": 0.0, "vy": 0.0, "wz": -0.38 * sign})]}
        a, b = os.path.join(d, "a.json"), os.path.join(d, "b.json")
        with open(a, "w") as f:
            json.dump(summary(1, 0.18), f)
        with open(b, "w") as f:
            json.dump(summary(-1, 0.30), f)
        r = run("compare", a, b)
        last = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else ""
        if r.returncode != 0 or not last.startswith("sides differ by more than 15 % of the command: 1 of 3") \
                or "diag vy (0.60 / 1.00)" not in last:
            failures.append(f"compare: rc {r.returncode}, last line {last!r}, {r.stderr}")
        r = run("compare", a, a)
        if r.returncode == 0 or "not mirror images" not in r.stderr:
            failures.append(f"compare of a summary with itself: rc {r.returncode}, {r.stderr.strip()!r}")
    print("\n".join("FAIL: " + f for f in failures) if failures else "mirror_grid.py: mirror and compare as expected")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
