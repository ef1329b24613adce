#!/usr/bin/env bash
# Replay the product path's command to a trained actor's randomized robots in MJX, on a GPU machine of this
# workplace (training/README.md, appendix): the screen that gives MJX what the SIL gave the actor.
#   training/device_replay_job.sh SCHEDULE "RUN [RUN...]" SEED_CSV [SEED_CSV...]
# (on the device, from the repository root, with carry [".whl"]; $OUT set by the device runner.)
# Each RUN is .whl/RUN/ holding actor.npz and train_config.json; SCHEDULE (a copy in .whl/: training/results is out
# of the reduced tree) names the segments; each SEED_CSV is a seed<k>.csv of `pmg_policy_sil --commands SCHEDULE
# --out DIR` (its command after the controller's shaper, feed-forward and feedback: eval_mjx.py --command-log).
# For every RUN and SEED_CSV, 128 robots of the run's training distribution (--randomized 128 --seed 1, the robots
# of every MJX screen) play that command; the runs go side by side on the one GPU, the CSVs one after the other.
# Writes $OUT/replay_RUN_<csv name>.txt (eval_mjx's report: robots fallen per segment) and .json
# (segment_robots.py's summary).
set -u
[ $# -ge 3 ] || { echo "usage: training/device_replay_job.sh SCHEDULE \"RUN [RUN...]\" SEED_CSV [SEED_CSV...]" >&2; exit 2; }
sched=$1; runs=$2; shift 2
mkdir -p /tmp/site /tmp/replay && tar xzf .whl/site.tgz -C /tmp/site || exit 1
export PYTHONPATH=/tmp/site XLA_PYTHON_CLIENT_PREALLOCATE=false
replay() {
  local R=$1 csv name
  shift
  for csv in "$@"; do
    name=replay_${R}_$(basename "$csv" .csv)
    JAX_COMPILATION_CACHE_DIR=/tmp/jc_$R timeout 8m python3 training/eval_mjx.py .whl/$R/actor.npz \
      --train-config .whl/$R/train_config.json --commands "$sched" --command-log "$csv" --randomized 128 --seed 1 \
      --out /tmp/replay/$name.npz > $OUT/$name.txt 2>&1
    echo "rc $?" >> $OUT/$name.txt
    python3 training/segment_robots.py summarize /tmp/replay/$name.npz --commands "$sched" --out $OUT/$name.json \
      >> $OUT/$name.txt 2>&1
  done
}
for R in $runs; do replay "$R" "$@" & done
wait
