#!/bin/bash
# device job (one H200): train N24g = N24b's argv (seed 91, half the exploration noise) + --stop-keeps-posture 0.5;
# then (only if training exited 0) its nominal crouched_backward.yaml rollout and 128 randomized robots.
mkdir -p /tmp/site && tar xzf .whl/site.tgz -C /tmp/site
export PYTHONPATH=/tmp/site
mkdir -p /tmp/runs/rand
R=N24g
C=/tmp/runs/$R
JAX_COMPILATION_CACHE_DIR=/tmp/jc timeout 21m python3 $(cat .whl/argv_$R.txt) > /tmp/runs/$R.log 2>&1
rc=$?
echo "train rc $rc" >> /tmp/runs/$R.log
touch /tmp/runs/$R.trained
if [ $rc -ne 0 ]; then echo done > /tmp/runs/done; exit 1; fi
XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 5m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/crouched_backward.yaml --out /tmp/runs/${R}_cb.npz > /tmp/runs/mjx_crouched_backward_$R.txt 2>&1 &
XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 6m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/crouched_backward_short.yaml --randomized 128 --seed 1 --out /tmp/runs/rand/$R.npz > /tmp/runs/rand/mjx_rand_$R.txt 2>&1
echo "rc $?" >> /tmp/runs/rand/mjx_rand_$R.txt
python3 training/segment_robots.py summarize /tmp/runs/rand/$R.npz --commands .whl/crouched_backward_short.yaml --out /tmp/runs/rand/rand_$R.json >> /tmp/runs/rand/mjx_rand_$R.txt 2>&1
wait
echo done > /tmp/runs/done
