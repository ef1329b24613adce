#!/usr/bin/env bash
# One or more runs and their MJX screens on a GPU machine of this workplace (training/README.md, appendix).
#   training/device_screen_job.sh RUN [RUN...]   (on the device, from the repository root, with carry [".whl"])
# A RUN with no .whl/argv_RUN.txt but a .whl/RUN/ holding actor.npz and train_config.json is screened without training
# (a run whose machine was taken back before its screens; its files came back through device_poll.sh).
# Needs in .whl/: site.tgz (training/make_device_site.sh), argv_RUN.txt for each RUN (train_pmg.py's argv, --out
# /tmp/runs/RUN), whatever those argvs name there (e.g. vG_train_config.json), floor_stops_0.62.yaml,
# floor_transitions_0.62.yaml and crouched_backward_short.yaml (copies of
# training/results/fidelity/crouched/floor_stops_0.62.yaml, .../crouched/floor_transitions_0.62.yaml and
# .../flight_penalty/crouched_backward_short.yaml: training/results is out of the reduced tree). Several RUNs train
# side by side, one per GPU where the machine has as many (run i on GPU i mod N), else sharing (each under a
# 21-minute timeout); then each run that exited 0 rolls 128 randomized
# robots (--seed 1, the robots of every earlier screen) over each schedule (the transitions one after the other two), and segment_robots.py summarizes them.
# Writes /tmp/runs/RUN/, /tmp/runs/RUN.log, /tmp/runs/rand/ and, at the end, /tmp/runs/done. Start it with setsid in
# the background and poll with training/device_poll.sh "RUN [RUN...]" SECONDS.
set -u
[ $# -ge 1 ] || { echo "usage: training/device_screen_job.sh RUN [RUN...]" >&2; exit 2; }
mkdir -p /tmp/site /tmp/runs/rand && tar xzf .whl/site.tgz -C /tmp/site || { echo done > /tmp/runs/done; exit 1; }
export PYTHONPATH=/tmp/site
# On a machine with several GPUs (nvidia-h100-x2 and up) run i trains on GPU i mod N; runs that share a GPU take its
# memory as they need it.
NGPU=$(nvidia-smi -L 2>/dev/null | grep -c '^GPU')
[ "$NGPU" -ge 1 ] || NGPU=1
[ $# -gt "$NGPU" ] && export XLA_PYTHON_CLIENT_PREALLOCATE=false
declare -A GPU
i=0; for R in "$@"; do GPU[$R]=$(( i % NGPU )); i=$(( i + 1 )); done
echo "$# run(s) on $NGPU GPU(s): $(for R in "$@"; do printf '%s->%s ' "$R" "${GPU[$R]}"; done)"
train() {
  if [ ! -f .whl/argv_$1.txt ] && [ -f .whl/$1/actor.npz ]; then  # screen only: a run trained earlier (e.g. on a machine
    mkdir -p /tmp/runs/$1 && cp .whl/$1/actor.npz .whl/$1/train_config.json /tmp/runs/$1/  #   taken back before its screens)
    echo "screen only: .whl/$1/ (trained earlier)" > /tmp/runs/$1.log; touch /tmp/runs/$1.trained; return
  fi
  CUDA_VISIBLE_DEVICES=${GPU[$1]} JAX_COMPILATION_CACHE_DIR=/tmp/jc_$1 timeout 21m python3 $(cat .whl/argv_$1.txt) \
    > /tmp/runs/$1.log 2>&1
  echo "train rc $?" >> /tmp/runs/$1.log
  touch /tmp/runs/$1.trained
}
for R in "$@"; do train "$R" & done
wait
export XLA_PYTHON_CLIENT_PREALLOCATE=false
screen() {
  local R=$1 C=/tmp/runs/$1
  grep -qE "train rc 0|screen only" /tmp/runs/$R.log || return 0
  export CUDA_VISIBLE_DEVICES=${GPU[$R]}
  JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval timeout 8m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
    --commands .whl/floor_stops_0.62.yaml --randomized 128 --seed 1 --out /tmp/runs/floor_$R.npz > /tmp/runs/rand/mjx_floor_stops_$R.txt 2>&1 &
  JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval2 timeout 8m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
    --commands .whl/crouched_backward_short.yaml --randomized 128 --seed 1 --out /tmp/runs/cb_$R.npz > /tmp/runs/rand/mjx_rand_$R.txt 2>&1
  echo "rc $?" >> /tmp/runs/rand/mjx_rand_$R.txt
  wait
  JAX_COMPILATION_CACHE_DIR=/tmp/jc_eval3 timeout 8m python3 training/eval_mjx.py $C/actor.npz --train-config $C/train_config.json \
    --commands .whl/floor_transitions_0.62.yaml --randomized 128 --seed 1 --out /tmp/runs/ft_$R.npz > /tmp/runs/rand/mjx_floor_transitions_$R.txt 2>&1
  python3 training/segment_robots.py summarize /tmp/runs/ft_$R.npz --commands .whl/floor_transitions_0.62.yaml \
    --out /tmp/runs/rand/floor_transitions_$R.json >> /tmp/runs/rand/mjx_floor_transitions_$R.txt 2>&1
  python3 training/segment_robots.py summarize /tmp/runs/cb_$R.npz --commands .whl/crouched_backward_short.yaml \
    --out /tmp/runs/rand/rand_$R.json >> /tmp/runs/rand/mjx_rand_$R.txt 2>&1
  python3 training/segment_robots.py summarize /tmp/runs/floor_$R.npz --commands .whl/floor_stops_0.62.yaml \
    --out /tmp/runs/rand/floor_stops_$R.json >> /tmp/runs/rand/mjx_floor_stops_$R.txt 2>&1
}
for R in "$@"; do screen "$R" & done
wait
echo done > /tmp/runs/done
