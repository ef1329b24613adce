#!/bin/bash
# device job (one H200): train N24f = N24c's argv (seed 90, half the exploration noise) + --reward-weight flight=-1.0;
# then its nominal crouched_backward.yaml rollout and 128 randomized robots on the short crouched backward schedule.
export PYTHONPATH=/tmp/site
mkdir -p /tmp/runs/rand
C=/tmp/runs/N24f
JAX_COMPILATION_CACHE_DIR=/tmp/jc timeout 21m python3 $(cat .whl/argv_N24f.txt) > /tmp/runs/N24f.log 2>&1
echo "train rc $?" >> /tmp/runs/N24f.log
touch /tmp/runs/N24f.trained
XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 5m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/crouched_backward.yaml --out /tmp/runs/N24f_cb.npz > /tmp/runs/mjx_crouched_backward_N24f.txt 2>&1 &
XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 6m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/crouched_backward_short.yaml --randomized 128 --seed 1 --out /tmp/runs/rand/N24f.npz > /tmp/runs/rand/mjx_rand_N24f.txt 2>&1
echo "rc $?" >> /tmp/runs/rand/mjx_rand_N24f.txt
python3 training/segment_robots.py summarize /tmp/runs/rand/N24f.npz --commands .whl/crouched_backward_short.yaml --out /tmp/runs/rand/rand_N24f.json >> /tmp/runs/rand/mjx_rand_N24f.txt 2>&1
wait
echo done > /tmp/runs/done
