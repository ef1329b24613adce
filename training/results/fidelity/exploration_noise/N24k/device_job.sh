#!/bin/bash
# device job (one H200): train N24k = N24b's argv with --seed 92 (the half-noise recipe on a fourth seed);
# then (only if training exited 0) 128 randomized robots on the short crouched backward
# schedule and 128 on floor_stops_0.62.yaml, side by side.
mkdir -p /tmp/site && tar xzf .whl/site.tgz -C /tmp/site
export PYTHONPATH=/tmp/site
mkdir -p /tmp/runs/rand
R=N24k
C=/tmp/runs/$R
JAX_COMPILATION_CACHE_DIR=/tmp/jc timeout 21m python3 $(cat .whl/argv_$R.txt) > /tmp/runs/$R.log 2>&1
rc=$?
echo "train rc $rc" >> /tmp/runs/$R.log
touch /tmp/runs/$R.trained
if [ $rc -ne 0 ]; then echo done > /tmp/runs/done; exit 1; fi
export XLA_PYTHON_CLIENT_PREALLOCATE=false
JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 6m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/floor_stops_0.62.yaml --randomized 128 --seed 1 --out /tmp/runs/floor_$R.npz > /tmp/runs/rand/mjx_floor_stops_$R.txt 2>&1 &
JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval2 timeout 6m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/crouched_backward_short.yaml --randomized 128 --seed 1 --out /tmp/runs/cb_$R.npz > /tmp/runs/rand/mjx_rand_$R.txt 2>&1
echo "rc $?" >> /tmp/runs/rand/mjx_rand_$R.txt
wait
python3 training/segment_robots.py summarize /tmp/runs/cb_$R.npz --commands .whl/crouched_backward_short.yaml --out /tmp/runs/rand/rand_$R.json >> /tmp/runs/rand/mjx_rand_$R.txt 2>&1
python3 training/segment_robots.py summarize /tmp/runs/floor_$R.npz --commands .whl/floor_stops_0.62.yaml --out /tmp/runs/rand/floor_stops_$R.json >> /tmp/runs/rand/mjx_floor_stops_$R.txt 2>&1
echo done > /tmp/runs/done
