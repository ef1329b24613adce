#!/bin/bash
# The product-path evaluation of F11 and F12 (README "F11 and F12"): the default config with the run's ONNX (H10a's feed-forward),
# deep stand seeds 0-1 and crouched probe 36-38, then probe 39-41 and the grid 0-2; two runs at a time.
#   training/results/fidelity/action_range/eval_sil.sh F11 F12   (from the repository root)
cd "$(dirname "$0")/../../../.."
B=build/bin/pmg_policy_sil
for R in "$@"; do
  M=training/results/fidelity/action_range/$R/g1_pmg_policy.onnx; O=training/results/fidelity/action_range/$R/sil; mkdir -p $O
  $B --model $M --commands training/results/fidelity/walking_height_fb/h10a_below_floor/deep_stand/deep_stand.yaml --seeds 2 --first-seed 0 --restart-after-fall --out $O/deep_stand > $O/deep_stand.log 2>&1 &
  $B --model $M --commands training/results/fidelity/crouched/probe_heights.yaml --seeds 3 --first-seed 36 --restart-after-fall --out $O/probe_36 > $O/probe_36.log 2>&1
  wait
  python3 scripts/segment_band.py $O/probe_36/summary.json > $O/probe_36_band.txt 2>&1
done
for R in "$@"; do
  M=training/results/fidelity/action_range/$R/g1_pmg_policy.onnx; O=training/results/fidelity/action_range/$R/sil
  $B --model $M --commands training/results/fidelity/crouched/probe_heights.yaml --seeds 3 --first-seed 39 --restart-after-fall --out $O/probe_39 > $O/probe_39.log 2>&1 &
  $B --model $M --commands config/policies/eval_envelope.yaml --seeds 3 --first-seed 0 --restart-after-fall --out $O/grid > $O/grid.log 2>&1
  wait
  python3 scripts/segment_band.py $O/probe_39/summary.json > $O/probe_39_band.txt 2>&1
  python3 scripts/segment_band.py $O/grid/summary.json > $O/grid_band.txt 2>&1
done
