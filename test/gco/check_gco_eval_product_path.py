#!/usr/bin/env python3
"""pmg_gco_eval --controller evaluates the product path: each grid command is shaped by the
controller config's `commands:` limits before the generator sees it, and the reference target is
checked against the shaped command. Usage: check_gco_eval_product_path.py PMG_GCO_EVAL CONTROLLER OUT_DIR

On a 2 x 2 grid (v_x 0 / 0.8 m/s, standing / crouched to 0.62 m) with g1_sil_policy.yaml (crouched
velocity envelope [0.3, 0.3, 0.6] at 0.62 m):
- the crouched 0.8 m/s command is shaped to 0.3 m/s, counted as slowed, and its reference carries
  0.3 m/s within the target; the standing 0.8 m/s command is not slowed and is carried;
- without --controller the same command is the target itself (0.8 m/s);
- --controller together with --blending (a setting the controller config owns) is refused."""
import csv
import os
import subprocess
import sys

exe, controller, out = sys.argv[1:4]
grid = ["--vx", "0", "0.8", "--vy", "0", "--wz", "0", "--pitch", "0", "--roll", "0", "--height", "0", "0.62",
        "--seconds", "2", "--warmup", "1"]
failures = []


def run(extra, sub):
    d = os.path.join(out, sub)
    os.makedirs(d, exist_ok=True)
    p = subprocess.run([exe, *grid, *extra, "--out-dir", d], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"FAIL: {extra}: exit {p.returncode}\n{p.stderr}")
    rows = {(float(r["vx"]), float(r["height"])): r for r in csv.DictReader(open(os.path.join(d, "gco_grid.csv")))}
    return p.stdout, rows


stdout, rows = run(["--controller", controller], "product")
crouched, standing = rows[(0.8, 0.62)], rows[(0.8, 0.0)]
if abs(float(crouched["target_vx"]) - 0.3) > 1e-6:
    failures.append(f"crouched 0.8 m/s shaped to {crouched['target_vx']}, expected 0.3 (crouched envelope)")
if crouched["within_target"] != "1" or abs(float(crouched["cycle_implied_vx"]) - 0.3) > 0.03:
    failures.append(f"crouched: reference implies {crouched['cycle_implied_vx']} m/s for the shaped 0.3")
if abs(float(standing["target_vx"]) - 0.8) > 1e-9 or standing["within_target"] != "1":
    failures.append(f"standing 0.8 m/s: target {standing['target_vx']}, within {standing['within_target']}")
if "product path: 1 of 4 commands slowed" not in stdout:
    failures.append("summary line 'product path: 1 of 4 commands slowed' missing")
_, raw = run([], "raw")
if abs(float(raw[(0.8, 0.62)]["target_vx"]) - 0.8) > 1e-9:
    failures.append(f"without --controller the target is {raw[(0.8, 0.62)]['target_vx']}, expected the command 0.8")
p = subprocess.run([exe, *grid, "--controller", controller, "--blending", "paper"], capture_output=True, text=True)
if p.returncode == 0 or "--blending" not in p.stderr + p.stdout:
    failures.append(f"--controller with --blending: exit {p.returncode}, expected a refusal naming --blending")
print("\n".join("FAIL: " + f for f in failures) if failures else
      "pmg_gco_eval --controller: shaped crouched command carried, standing unchanged, raw target kept, conflict refused")
sys.exit(1 if failures else 0)
