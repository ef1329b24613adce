#!/bin/bash
# device job (one H200): train N24c (V20b's recipe at half the exploration noise, seed 90); beside it, 128
# randomized robots of N24a and N24b on the short crouched backward schedule; then the same for N24c and its
# nominal crouched_backward.yaml rollout. Results under /tmp/runs.
export PYTHONPATH=/tmp/site
mkdir -p /tmp/runs/rand
rand() {  # actor train_config name
  XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 8m python3 training/eval_mjx.py $1 --train-config $2 \
    --commands .whl/crouched_backward_short.yaml --randomized 128 --seed 1 --out /tmp/runs/rand/$3.npz > /tmp/runs/rand/mjx_rand_$3.txt 2>&1
  echo "rc $?" >> /tmp/runs/rand/mjx_rand_$3.txt
  python3 training/segment_robots.py summarize /tmp/runs/rand/$3.npz --commands .whl/crouched_backward_short.yaml --out /tmp/runs/rand/rand_$3.json >> /tmp/runs/rand/mjx_rand_$3.txt 2>&1
}
JAX_COMPILATION_CACHE_DIR=/tmp/jc timeout 21m python3 $(cat .whl/argv_N24c.txt) > /tmp/runs/N24c.log 2>&1 &
TP=$!
sleep 60  # training takes its memory first
(rand .whl/N24a/actor.npz .whl/N24a/train_config.json N24a; rand .whl/N24b/actor.npz .whl/N24b/train_config.json N24b) &
wait $TP; echo "train rc $?" >> /tmp/runs/N24c.log
touch /tmp/runs/N24c.trained
C=/tmp/runs/N24c
XLA_PYTHON_CLIENT_PREALLOCATE=false JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 5m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
  --commands .whl/crouched_backward.yaml --out /tmp/runs/N24c_cb.npz > /tmp/runs/mjx_crouched_backward_N24c.txt 2>&1 &
rand $C/actor.npz $C/train_config.json N24c
wait
echo done > /tmp/runs/done
