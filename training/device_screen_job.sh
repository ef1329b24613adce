#!/usr/bin/env bash
# One from-scratch run and its MJX screen on a GPU machine of this workplace (training/README.md, appendix).
#   training/device_screen_job.sh RUN      (on the device, from the repository root, with carry [".whl"])
# Needs in .whl/: site.tgz (training/make_device_site.sh), argv_RUN.txt (train_pmg.py's argv, --out /tmp/runs/RUN),
# whatever that argv names there (e.g. vG_train_config.json), floor_stops_0.62.yaml and crouched_backward_short.yaml
# (copies of training/results/fidelity/crouched/floor_stops_0.62.yaml and .../flight_penalty/crouched_backward_short.yaml:
# training/results is out of the reduced tree). Trains under a 21-minute timeout; only if training exits 0 it rolls
# 128 randomized robots (--seed 1, the robots of every earlier screen) over each schedule, side by side, and
# summarizes them with segment_robots.py. Writes /tmp/runs/RUN/, /tmp/runs/RUN.log, /tmp/runs/rand/ and, at the
# end, /tmp/runs/done. Start it with setsid in the background and poll with training/device_poll.sh RUN SECONDS.
set -u
R=${1:?usage: training/device_screen_job.sh RUN}
mkdir -p /tmp/site /tmp/runs/rand && tar xzf .whl/site.tgz -C /tmp/site || { echo done > /tmp/runs/done; exit 1; }
export PYTHONPATH=/tmp/site
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
python3 training/segment_robots.py summarize /tmp/runs/cb_$R.npz --commands .whl/crouched_backward_short.yaml \
  --out /tmp/runs/rand/rand_$R.json >> /tmp/runs/rand/mjx_rand_$R.txt 2>&1
python3 training/segment_robots.py summarize /tmp/runs/floor_$R.npz --commands .whl/floor_stops_0.62.yaml \
  --out /tmp/runs/rand/floor_stops_$R.json >> /tmp/runs/rand/mjx_floor_stops_$R.txt 2>&1
echo done > /tmp/runs/done
