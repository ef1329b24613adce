#!/usr/bin/env python3
"""scripts/plot_segment_compare.py on two synthetic pmg_policy_sil summaries with known values: the
printed table carries each actor's achieved height and achieved/commanded ratios (a "-" where an
axis is not commanded), the standing segment is left out, the figure is written, and a segment
missing from one summary or a malformed summary is refused with the file or segment named."""
import json
import os
import subprocess
import sys
import tempfile

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "plot_segment_compare.py")


def summary(segments):
    keys = ("vx", "vy", "wz", "pitch", "roll", "height")
    return {"segments": [{"name": n, "command": dict(zip(keys, c)), "reference": dict(zip(keys, c)),
                          "achieved": dict(zip(keys, a))} for n, c, a in segments]}


failures = []
with tempfile.TemporaryDirectory() as tmp:
    a = os.path.join(tmp, "a.json")
    b = os.path.join(tmp, "b.json")
    with open(a, "w") as f:
        json.dump(summary([("stand", (0, 0, 0, 0, 0, 0.78), (0.01, 0, 0, 0, 0, 0.779)),
                           ("back", (-0.3, 0, 0, 0, 0, 0.78), (-0.24, 0.01, 0, 0, 0, 0.772)),
                           ("arc", (0.4, 0.1, 0.3, 0, 0, 0.78), (0.42, 0.05, 0.27, 0, 0, 0.766))]), f)
    with open(b, "w") as f:
        json.dump(summary([("stand", (0, 0, 0, 0, 0, 0.78), (0, 0, 0, 0, 0, 0.78)),
                           ("back", (-0.3, 0, 0, 0, 0, 0.78), (-0.3, 0, 0, 0, 0, 0.777)),
                           ("arc", (0.4, 0.1, 0.3, 0, 0, 0.78), (0.4, 0.1, 0.3, 0, 0, 0.774))]), f)
    png = os.path.join(tmp, "cmp.png")
    r = subprocess.run([sys.executable, SCRIPT, png, f"A={a}", f"B={b}"], capture_output=True, text=True)
    rows = {line.split()[0]: line.split()[1:] for line in r.stdout.splitlines() if line and line.split()[0] in ("stand", "back", "arc")}
    if r.returncode != 0 or not os.path.getsize(png):
        failures.append(f"exit {r.returncode}, figure {'written' if os.path.exists(png) else 'missing'}: {r.stderr}")
    if "stand" in rows:
        failures.append("the standing segment was drawn")
    if rows.get("back") != ["0.772", "0.80", "-", "-", "0.777", "1.00", "-", "-"]:
        failures.append(f"back row {rows.get('back')}")
    if rows.get("arc") != ["0.766", "1.05", "0.50", "0.90", "0.774", "1.00", "1.00", "1.00"]:
        failures.append(f"arc row {rows.get('arc')}")
    r = subprocess.run([sys.executable, SCRIPT, png, f"A={a}", f"B={b}", "--segments", "back,turn"], capture_output=True, text=True)
    if r.returncode == 0 or "'turn'" not in r.stderr:
        failures.append(f"a missing segment: exit {r.returncode}, {r.stderr.strip()!r}")
    bad = os.path.join(tmp, "bad.json")
    with open(bad, "w") as f:
        f.write("{}")
    r = subprocess.run([sys.executable, SCRIPT, png, f"A={bad}"], capture_output=True, text=True)
    if r.returncode == 0 or bad not in r.stderr:
        failures.append(f"a malformed summary: exit {r.returncode}, {r.stderr.strip()!r}")
print("\n".join("FAIL: " + f for f in failures) if failures else "plot_segment_compare: table, figure and refusals as expected")
sys.exit(1 if failures else 0)
