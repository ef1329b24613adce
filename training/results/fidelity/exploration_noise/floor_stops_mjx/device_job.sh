#!/bin/bash
# device job: N24b and N24g, 128 randomized robots each in MJX on floor_stops_0.62.yaml (results written straight to $OUT)
mkdir -p /tmp/site && tar xzf .whl/site.tgz -C /tmp/site
export PYTHONPATH=/tmp/site XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc
for R in N24b N24g; do
  timeout 300 python3 training/eval_mjx.py training/results/fidelity/exploration_noise/$R/actor.npz --train-config training/results/fidelity/exploration_noise/$R/train_config.json \
    --commands training/results/fidelity/crouched/floor_stops_0.62.yaml --randomized 128 --seed 1 --out /tmp/floor_$R.npz > $OUT/mjx_floor_stops_$R.txt 2>&1 &
done
wait
for R in N24b N24g; do
  python3 training/segment_robots.py summarize /tmp/floor_$R.npz --commands training/results/fidelity/crouched/floor_stops_0.62.yaml --out $OUT/floor_stops_$R.json >> $OUT/mjx_floor_stops_$R.txt 2>&1
done
ls -la $OUT
