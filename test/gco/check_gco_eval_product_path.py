#!/usr/bin/env python3
"""pmg_gco_eval --controller evaluates the product path: each grid command is shaped by the
controller config's `commands:` limits before the generator sees it, and the reference target is
checked against the shaped command. Usage: check_gco_eval_product_path.py PMG_GCO_EVAL CONTROLLER OUT_DIR

On a 2 x 2 grid (v_x 0 / 0.8 m/s, standing / crouched to 0.62 m) with g1_sil_policy_wh6g.yaml (crouched
velocity envelope [0.3, 0.3, 0.6] at 0.62 m, walking height floor 0.66 m):
- the crouched 0.8 m/s command is walked at the floor's height and shaped to what the envelope allows
  there (the CommandLimits rule, computed here from the config and the squat clip's standing height:
  more than the 0.3 m/s it allows at 0.62 m), counted as slowed, and its reference carries the shaped
  speed within the target; the standing 0.8 m/s command is not slowed and is carried;
- without --controller the same command is the target itself (0.8 m/s);
- --controller together with --blending (a setting the controller config owns) is refused."""
import csv
import os
import subprocess
import sys

import yaml

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




def envelope_vx(controller_path, vx, height):
    """The shaped v_x of a single-axis command at a shaped height (CommandLimits::crouched_height docstring):
    s = (1 - f) |u| / M + f |u| / m(f), m(f) = M + f (m_crouched - M), f = (standing - h) / (standing - crouched)."""
    config = yaml.safe_load(open(controller_path))
    cmd = config["commands"]
    squat = yaml.safe_load(open(os.path.join(os.path.dirname(controller_path), config["clips"], "squat.yaml")))
    standing = float(squat["neutral"])
    h = max(height, float(cmd.get("walking_min_height", 0.0)))
    f = min(max((standing - h) / (standing - float(cmd["crouched_height"])), 0.0), 1.0)
    big, small = float(cmd["max_velocity"][0]), float(cmd["crouched_max_velocity"][0])
    scale = (1 - f) * vx / big + f * vx / (big + f * (small - big))
    return vx / scale if scale > 1 else vx


stdout, rows = run(["--controller", controller], "product")
crouched, standing = rows[(0.8, 0.62)], rows[(0.8, 0.0)]
expected = envelope_vx(controller, 0.8, 0.62)
if not 0.3 < expected < 0.8 or abs(float(crouched["target_vx"]) - expected) > 1e-6:
    failures.append(f"crouched 0.8 m/s shaped to {crouched['target_vx']}, expected {expected:.4f} (the crouched "
                    f"envelope at the walking height floor; more than its 0.3 at 0.62 m)")
if crouched["within_target"] != "1" or abs(float(crouched["cycle_implied_vx"]) - expected) > 0.1 * expected:
    failures.append(f"crouched: reference implies {crouched['cycle_implied_vx']} m/s for the shaped {expected:.3f}")
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
