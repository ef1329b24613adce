#!/usr/bin/env bash
# Poll a training/device_screen_job.sh on the device: wait up to SECONDS (less when the job is done), print each
# log's tail, the progress and the GPU, and pack each run (actor, ONNX, progress, config; not params.pkl, the kept
# actors or the rollouts' .npz, which pass the 16 MiB a returned file may have) with the screens' text into
# $OUT/RUN.tgz. The last four kept actors (--keep-actors, 0.8 MB each) go into $OUT/RUN_actors.tgz, for screening
# them later. It packs once a minute while it waits, not only at the end: a call cut short by the session's device
# budget (the run's limit_s is then below SECONDS) still returns the last minute's state, since $OUT comes back on a
# timeout. Two files per run come back, and a call returns at most 8: poll at most four runs.
#   training/device_poll.sh "RUN [RUN...]" SECONDS
RUNS=${1:?usage: training/device_poll.sh \"RUN [RUN...]\" SECONDS}
# A machine that was handed back (30 s without a command) and started afresh has no job: say so and stop at once
# instead of waiting out SECONDS on an empty machine (training/README.md, appendix: "A turn cut off between two calls").
if [ ! -d /tmp/runs ]; then echo "no /tmp/runs: this is a fresh machine, the job was lost with the previous one"; exit 3; fi
end=$(( $(date +%s) + ${2:?usage: training/device_poll.sh \"RUN [RUN...]\" SECONDS} ))
pack() {
  local R last
  for R in $RUNS; do
    [ -d /tmp/runs/$R ] || continue
    tar czf $OUT/$R.tgz.part -C /tmp/runs --exclude=$R/actors --exclude=$R/params.pkl $R $R.log rand \
      $(cd /tmp/runs; ls $R.trained done 2>/dev/null) && mv $OUT/$R.tgz.part $OUT/$R.tgz
    last=$(ls /tmp/runs/$R/actors 2>/dev/null | tail -n 4)
    if [ -n "$last" ]; then
      tar czf $OUT/${R}_actors.tgz.part -C /tmp/runs/$R/actors $last && mv $OUT/${R}_actors.tgz.part $OUT/${R}_actors.tgz
    fi
  done
}
next=$(( $(date +%s) + 60 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do
  sleep 10
  if [ $(date +%s) -ge $next ]; then pack; next=$(( $(date +%s) + 60 )); fi
done
date
for R in $RUNS; do echo "== $R"; tail -n 4 /tmp/runs/$R.log; wc -l /tmp/runs/$R/progress.jsonl 2>/dev/null; done; echo
nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
pack
ls -la $OUT
