#!/usr/bin/env python3
"""Checks the command-response feed-forward through the product path (ctest pmg_policy_sil_feedforward,
label sil): the default config (velocity_feedback.feedforward on) runs test/data/policy/eval_feedforward.yaml
(a right arc from standing, then a stop) with the feed-forward off and on
(pmg_policy_sil --feedforward off|on --seeds 1). From the per-tick CSV (vx_cmd..wz_cmd: the command u;
vx_fb..wz_fb: what the generator got, u_fb = u_ff + c):
- in the arc, after the command's ramp and before the integral correction may act (settle_time_s
  after the command is steady), u_fb is u off, and on the model's inverse of u (within 2e-3: the
  correction has integrated at most that during the ramp's steady stretches),
  computed here independently from the config's coefficients (the documented Gauss-Seidel rule,
  include/pmg/controller/velocity_feedback.hpp) and kept inside the feedback's limits; the arc moves all
  three axes, so its bound is max_correction shrunk by combined_max_correction_ratio (the test runs with
  --combined-ff-ratio 0.5, which summary.json records as combined_ff_ratio);
- there the inverse differs from u by more than 0.02 on some axis (the test would notice a model
  that is not applied);
- standing, before the arc and at the end of the stop, u_fb is zero on and off (a robot told to
  stand is not moved);
- u_fb never steps: at most 0.03 per tick on every axis, on and off, through the ramp and the stop;
- no fall.
Usage: check_sil_feedforward.py CONFIG OFF_DIR ON_DIR
"""
import math
import os
import sys

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sil_run import rows, window  # noqa: E402

AX = ("vx", "vy", "wz")


def inverse(ff, u, lo, hi, ratio):
    """CommandResponseModel::invert, written again from its documentation; @p ratio is
    combined_max_correction_ratio (the bound shrinks on a three-axis command)."""
    full = ff.get("combined_full", [0.2, 0.15, 0.25])
    kappa = 1.0
    for j in range(3):
        kappa *= min(1.0, abs(u[j]) / full[j])
    shrink = 1.0 - (1.0 - ratio) * kappa
    x = list(u)
    for _ in range(ff.get("iterations", 8)):
        for i, a in enumerate(AX):
            e = ff[a]
            r = u[i]
            gain = 0.0
            for j in range(3):
                if j == i:
                    continue
                r -= e.get("drift", [0, 0, 0])[j] * x[j]
                gain += e.get("gain_per_magnitude", [0, 0, 0])[j] * abs(x[j]) + e.get("gain_per_command", [0, 0, 0])[j] * x[j]
            gain += e.get("gain_positive", 1.0) if r >= 0 else e.get("gain_negative", 1.0)
            mc = ff.get("max_correction", [0.3, 0.2, 0.4])[i] * shrink
            x[i] = min(max(r / max(ff.get("min_gain", 0.5), gain), u[i] - mc), u[i] + mc)
    return [min(max(x[i], min(lo[i], u[i])), max(hi[i], u[i])) for i in range(3)]


def main():
    config, off_dir, on_dir = sys.argv[1:4]
    with open(config) as f:
        c = yaml.safe_load(f)
    vf = c["velocity_feedback"]
    ff = vf["feedforward"]
    assert ff.get("enabled"), f"{config}: velocity_feedback.feedforward is off"
    maxv = c["commands"]["max_velocity"]
    lo = [max(vf["envelope_min"][i], -maxv[i]) for i in range(3)]
    hi = [min(vf["envelope_max"][i], maxv[i]) for i in range(3)]
    settle = vf.get("settle_time_s", 0.5)
    failures = []
    runs = {"off": rows(off_dir), "on": rows(on_dir)}
    for label, (summary, rs) in runs.items():
        ratio = summary.get("combined_ff_ratio")
        if ratio is None:
            failures.append(f"{label}: summary.json does not record combined_ff_ratio")
            ratio = ff.get("combined_max_correction_ratio", 1.0)
        if summary["runs"][0]["fell"]:
            failures.append(f"{label}: the robot fell")
        # After the 0.5 s ramp, before the correction may integrate (settle_time_s after steady).
        win = window(rs, "arc_r", 0.55, 0.5 + settle - 0.05)
        assert len(win) >= 5, f"{label}: {len(win)} ticks in the check window"
        for r in win:
            u = [r[f"{a}_cmd"] for a in AX]
            want = inverse(ff, u, lo, hi, ratio) if label == "on" else u
            got = [r[f"{a}_fb"] for a in AX]
            for i in range(3):
                if not abs(got[i] - want[i]) <= 2e-3:
                    failures.append(f"{label}: t {r['t']:.2f} {AX[i]}_fb {got[i]:.5f}, expected {want[i]:.5f} (u {u[i]:.3f})")
        if label == "on":
            u = [win[0][f"{a}_cmd"] for a in AX]
            moved = max(abs(a - b) for a, b in zip(inverse(ff, u, lo, hi, ratio), u))
            if moved <= 0.02:
                failures.append(f"on: the model's inverse moves u {u} by only {moved:.4f}: nothing to check")
            print(f"arc u {u} -> u_ff {[round(x, 4) for x in inverse(ff, u, lo, hi, ratio)]} (combined_ff_ratio {ratio})")
        for name, t0, t1 in (("stand", 0.5, 2.0), ("stop", 3.0, 4.0)):
            for r in window(rs, name, t0, t1):
                if any(abs(r[f"{a}_fb"]) > 1e-9 for a in AX):
                    failures.append(f"{label}: standing in {name} at t {r['t']:.2f}, u_fb "
                                    f"({r['vx_fb']:.4f}, {r['vy_fb']:.4f}, {r['wz_fb']:.4f}) is not zero")
                    break
        fb = [r for r in rs if all(math.isfinite(r[f"{a}_fb"]) for a in AX)]
        if len(fb) < 0.9 * len(rs):
            failures.append(f"{label}: u_fb is not finite in {len(rs) - len(fb)} of {len(rs)} ticks")
        step = max(abs(b[f"{a}_fb"] - a_[f"{a}_fb"]) for a_, b in zip(fb, fb[1:]) for a in AX)
        print(f"{label}: largest step of u_fb per tick {step:.4f}")
        if step > 0.03:
            failures.append(f"{label}: u_fb steps by {step:.4f} in one tick (bound 0.03)")
        arc = next(s for s in summary["segments"] if s["name"] == "arc_r")
        print(f"{label}: arc achieved " + ", ".join(f"{a} {arc['achieved'][a]:+.3f}" for a in AX))
    if failures:
        print("FAIL\n  " + "\n  ".join(failures[:20]))
        sys.exit(1)
    print("OK")


if __name__ == "__main__":
    main()
