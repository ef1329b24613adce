#!/usr/bin/env python3
"""Tests scripts/fit_command_response.py (ctest fit_command_response_finds_a_hidden_coupling, label
unit) on synthetic pmg_policy_sil summaries with a known response hidden in them:
- v_x: 0.95 of a forward command, 0.8 of a backward one upright, the backward gain rising by 5 per
  metre of crouch (crouched to 0.70 m a backward walk overshoots: 1.2), nothing else;
- v_y: 0.9 / 0.85, the gain falling by 0.4 per rad/s of |w| (a turn slows the side-step), and a
  drift of -0.06 per rad/s of w;
- w: 0.9 either way, the gain falling by 0.2 per m/s of |v_x|;
each seed's value with Gaussian noise (0.01), 120 random commands at the standing height in two
summaries of 2 seeds each, and 60 at heights 0.60-0.78 m in a third (below the walking floor 0.66 m the
robot walks at 0.66 m: the crouch is at most 0.12 m); one seed's segment an upset (achieved far from the
command) and one segment with a fall.
The fit must recover every hidden coefficient within 0.05 (the gains), 0.06 (the couplings) or 0.8 per
metre (the crouch terms, whose column is at most 0.12 x the command), choose by the one-standard-error
rule exactly the term groups that carry them (v_x G+C, v_y G+M+D, w G+M; the lowest CV error alone
takes a coupling of v_x's fitted to the noise), no coupling of v_x's beyond 0.05, report the upset and the fall as left out, and write a block that
the controller's keys accept (its max_correction given). Without the crouched summary the crouch terms
stay 0. The report's per-regime line shows v_x's crouched backward walks missed by the gains alone and
carried to the noise by the chosen G+C. The crouch is measured from the standing height the summaries record (0.78 here; the default
for summaries without it is 0.7645, which would shift v_x's backward gain by 0.08), and summaries of
two standing heights are refused.
Usage: test_fit_command_response.py
"""
import os
import random
import re
import subprocess
import sys
import tempfile

import json

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
AX = ("vx", "vy", "wz")


STANDING, FLOOR = 0.78, 0.66


def truth(u, height):
    vx, vy, wz = u
    crouch = STANDING - max(height, FLOOR)
    ax = (0.95 if vx >= 0 else 0.8 + 5.0 * crouch) * vx
    ay = ((0.9 if vy >= 0 else 0.85) - 0.4 * abs(wz)) * vy - 0.06 * wz
    aw = (0.9 - 0.2 * abs(vx)) * wz
    return [ax, ay, aw]


def summary(rng, n, first_name, upset=False, fall=False, crouched=False):
    segs, runs = [], [{"seed": s, "segments": []} for s in range(2)]
    for k in range(n):
        u = [rng.uniform(-0.5, 1.0), rng.uniform(-0.4, 0.4), rng.uniform(-0.8, 0.8)]
        height = round(rng.uniform(0.60, STANDING), 3) if crouched else STANDING
        name = f"r{first_name + k:03d}"
        per_seed = []
        for s in range(2):
            v = [x + rng.gauss(0.0, 0.01) for x in truth(u, height)]
            if upset and k == 3 and s == 1:
                v = [-0.9, 0.6, 0.0]
            per_seed.append(v)
            runs[s]["segments"].append({"name": name, "achieved": dict(zip(AX, v))})
        mean = [sum(v[i] for v in per_seed) / 2 for i in range(3)]
        segs.append({"name": name, "seeds": 2, "fallen": 1 if (fall and k == 5) else 0,
                     "command": {**dict(zip(AX, u)), "pitch": 0, "roll": 0, "height": height},
                     "achieved": {**dict(zip(AX, mean)), "pitch": 0, "roll": 0, "height": max(height, FLOOR)}})
    # What pmg_policy_sil records: the controller's standing height and walking floor (the crouch's zero and floor).
    return {"standing_height": STANDING, "walking_min_height": FLOOR, "segments": segs, "runs": runs}


def fit(d, paths, tag):
    out_yaml = os.path.join(d, f"ff_{tag}.yaml")
    out = subprocess.run([sys.executable, os.path.join(ROOT, "scripts/fit_command_response.py"), *paths,
                          "--out", out_yaml, "--max-correction", "0.15,0.1,0.15"],  # the heights from the summaries
                         capture_output=True, text=True, check=True).stdout
    print(out)
    return out, open(out_yaml).read()


def coeffs(text, axis):
    m = re.search(rf"  {axis}: \{{gain_positive: ([-\d.]+), gain_negative: ([-\d.]+), gain_per_magnitude: \[([^\]]*)\], "
                  rf"gain_per_command: \[([^\]]*)\], drift: \[([^\]]*)\], gain_positive_per_crouch: ([-\d.]+), "
                  rf"gain_negative_per_crouch: ([-\d.]+)\}}", text)
    assert m, f"no {axis} line in:\n{text}"
    vec = lambda s: [float(x) for x in s.split(",")]  # noqa: E731
    return (float(m.group(1)), float(m.group(2)), vec(m.group(3)), vec(m.group(4)), vec(m.group(5)),
            float(m.group(6)), float(m.group(7)))


def main():
    rng = random.Random(7)
    failures = []
    with tempfile.TemporaryDirectory() as d:
        paths = []
        for i, s in enumerate((summary(rng, 60, 0, upset=True), summary(rng, 60, 60, fall=True),
                               summary(rng, 60, 120, crouched=True))):
            paths.append(os.path.join(d, f"s{i}.json"))
            with open(paths[-1], "w") as f:
                json.dump(s, f)
        out, text = fit(d, paths, "all")
        # Upright sweeps alone (their v_x gain is the upright one): no crouch term is made up.
        out_upright, text_upright = fit(d, paths[:2], "upright")
        # Runs of another controller (another standing height) are not fitted together: refused, naming both.
        other = summary(rng, 30, 200, crouched=True)
        other["standing_height"] = 0.7645
        paths.append(os.path.join(d, "other.json"))
        with open(paths[-1], "w") as f:
            json.dump(other, f)
        mixed = subprocess.run([sys.executable, os.path.join(ROOT, "scripts/fit_command_response.py"), *paths,
                                "--out", os.path.join(d, "mixed.yaml")], capture_output=True, text=True)
    if mixed.returncode == 0 or "standing_height 0.7645" not in mixed.stderr or "s0.json" not in mixed.stderr:
        failures.append(f"summaries of two standing heights fitted together (exit {mixed.returncode}): {mixed.stderr.strip()}")
    for axis in AX:
        got = coeffs(text_upright, axis)
        if got[5] != 0.0 or got[6] != 0.0:
            failures.append(f"{axis}: crouch terms {got[5]} / {got[6]} fitted from upright sweeps alone")
    if "0 of them crouched" not in out_upright or "60 of them crouched" not in out:
        failures.append("the report does not count the crouched commands (0 upright, 60 with the crouched sweep)")

    want = {"vx": (0.95, 0.8, [0, 0, 0], [0, 0, 0], [0, 0, 0], 0.0, 5.0),
            "vy": (0.9, 0.85, [0, 0, -0.4], [0, 0, 0], [0, 0, -0.06], 0.0, 0.0),
            "wz": (0.9, 0.9, [-0.2, 0, 0], [0, 0, 0], [0, 0, 0], 0.0, 0.0)}
    for axis, (gp, gn, mag, cmd, drift, kp, kn) in want.items():
        got = coeffs(text, axis)
        if abs(got[0] - gp) > 0.05 or abs(got[1] - gn) > 0.05:
            failures.append(f"{axis}: gains {got[0]:.3f} / {got[1]:.3f}, hidden {gp} / {gn}")
        if abs(got[5] - kp) > 0.8 or abs(got[6] - kn) > 0.8:
            failures.append(f"{axis}: gains per crouch {got[5]:.3f} / {got[6]:.3f} 1/m, hidden {kp} / {kn}")
        for name, g, w in (("gain_per_magnitude", got[2], mag), ("gain_per_command", got[3], cmd), ("drift", got[4], drift)):
            for j in range(3):
                if abs(g[j] - w[j]) > 0.06:
                    failures.append(f"{axis}.{name}[{j}] {g[j]:.3f}, hidden {w[j]}")
    # The one-standard-error rule picks exactly the hidden structure; the lowest CV error alone took v_x's
    # G+S+C here (a signed coupling fitted to the noise).
    for axis, terms in (("vx", "G+C"), ("vy", "G+M+D"), ("wz", "G+M")):
        if not re.search(rf"# {axis}: .*-> {re.escape(terms)}$", out, re.M):
            failures.append(f"{axis}: the chosen terms are not the hidden {terms}")
    if not re.search(r"# vx: .*-> G$", out_upright, re.M):
        failures.append("v_x's terms from the upright sweeps are not the gains alone")
    # The per-regime split shows where the crouch term acts: v_x's crouched backward walks, which the gains
    # alone (G) miss most (by the hidden overshoot) and the chosen G+C carries to the noise, as every regime.
    m = re.search(r"# vx per regime, cross-validated RMSE identity/G/chosen G\+C \(commands\): (.*)$", out, re.M)
    if not m:
        failures.append("no per-regime line for v_x")
    else:
        cells = dict((c.group(1), (float(c.group(2)), float(c.group(3)), float(c.group(4)), int(c.group(5))))
                     for c in re.finditer(r"(upright [+-]|crouched [+-]) ([\d.]+)/([\d.]+)/([\d.]+) \((\d+)\)", m.group(1)))
        walking = sum(n for *_, n in cells.values())
        if len(cells) != 4 or not 150 <= walking <= 180:
            failures.append(f"v_x regimes {sorted(cells)} over {walking} commands (180 drawn; a command with |v_x| under 0.05 m/s is in no regime)")
        else:
            _, g_cb, chosen_cb, _ = cells["crouched -"]
            if not (g_cb > 2.0 * chosen_cb and g_cb == max(c[1] for c in cells.values())):
                failures.append(f"v_x crouched backward: G {g_cb} against G+C {chosen_cb}; the crouch term's regime is not shown")
            if max(c[2] for c in cells.values()) > 0.02:
                failures.append(f"v_x regimes {cells}: the chosen G+C is beyond the noise in one of them")
    if "upset left out" not in out or "1 upsets" not in out:
        failures.append("the upset is not reported as left out")
    if "2 with a fall" not in out:
        failures.append("the fallen segment's two seeds are not reported as left out")
    if "max_correction: [0.15, 0.1, 0.15]" not in text or "enabled: true" not in text:
        failures.append("the block lacks enabled or the given max_correction")
    if failures:
        print("FAIL\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("OK")


if __name__ == "__main__":
    main()
