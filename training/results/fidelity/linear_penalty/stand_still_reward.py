#!/usr/bin/env python3
"""Per-step reward of a robot that stands still, perfectly upright at the standing height, under the
training command distribution of V20b's recipe (NumPy replay of G1PmgEnv._sample_command), with and
without the linear penalties. Imitation terms (ref_q, ref_qd, contact) are taken at their upper bound
(full credit) so the estimate is an upper bound on the stand-still reward."""
import json, sys
import numpy as np
cfg = json.load(open(sys.argv[1]))["env"]
rng = np.random.default_rng(0)
N = 2_000_000
v = rng.uniform([cfg["vx"][0], cfg["vy"][0], cfg["wz"][0]], [cfg["vx"][1], cfg["vy"][1], cfg["wz"][1]], (N, 3))
kind = rng.uniform(size=N)
single = kind < cfg["p_single_axis"]
combined = (kind >= cfg["p_single_axis"]) & (kind < cfg["p_single_axis"] + cfg["p_combined"])
axis = rng.integers(0, 3, N); one = np.eye(3)[axis]
two = rng.uniform(size=N) < cfg["p_two_axes"]
mask = np.where(single[:, None], one, np.where(combined[:, None], np.where(two[:, None], 1 - one, 1.0), 0.0))
v = v * mask
walking = single | combined
post = rng.uniform([cfg["pitch"][0], cfg["roll"][0], cfg["height"][0]], [cfg["pitch"][1], cfg["roll"][1], cfg["height"][1]], (N, 3))
neutral = np.array([0, 0, 0.78])
axes = rng.uniform(size=(N, 3)) < cfg["p_posture_axis"]
none = ~axes.any(1); axes[none] = np.eye(3)[rng.integers(0, 3, none.sum())] > 0
p_post = np.where(walking, cfg["p_posture_walk"], cfg["p_posture_stand"])
commanded = rng.uniform(size=N) < p_post
post = np.where((commanded[:, None] & axes), post, neutral)
w = cfg["w"]
for label, sig_v, sig_h in (("warm-up widths", 0.25, 0.02), ("final widths", cfg["lin_vel_sigma"], cfg["height_sigma"])):
    lin2 = v[:, 0] ** 2 + v[:, 1] ** 2; yaw2 = v[:, 2] ** 2
    r = (w["lin_vel"] * np.exp(-lin2 / sig_v) + w["yaw_rate"] * np.exp(-yaw2 / sig_v)
         + w["orientation"] * np.exp(-(post[:, 0] ** 2 + post[:, 1] ** 2) / cfg["orientation_sigma"])
         + w["height"] * np.exp(-(post[:, 2] - 0.78) ** 2 / sig_h) + w["ref_q"] + w["ref_qd"] + w["contact"] + w["alive"])
    pen = w.get("lin_vel_abs", 0.0) * np.sqrt(lin2) + w.get("yaw_rate_abs", 0.0) * np.sqrt(yaw2)
    for name, rr in (("without linear terms", r), ("with linear terms", r + pen)):
        # gamma 0.97: standing still forever is worth rr / (1 - gamma); falling now, termination -10
        worse = rr / (1 - 0.97) < w["termination"]
        print(f"{label:15s} {name:21s}: stand-still reward per step mean {rr.mean():.2f}, p5 {np.percentile(rr, 5):.2f}, "
              f"min {rr.min():.2f}; <= 0 for {100 * np.mean(rr <= 0):.1f} % of draws; falling at once pays more for {100 * np.mean(worse):.1f} %")
