#!/usr/bin/env bash
# Poll a training/device_screen_job.sh RUN on the device: wait up to SECONDS (less when the job is done), print
# the log's tail, the progress and the GPU, and pack the run (actor, ONNX, progress, config; not params.pkl, the kept
# actors or the rollouts' .npz, which pass the 16 MiB a returned file may have) with the screen's text into $OUT/RUN.tgz.
#   training/device_poll.sh RUN SECONDS
R=${1:?usage: training/device_poll.sh RUN SECONDS}
end=$(( $(date +%s) + ${2:?usage: training/device_poll.sh RUN SECONDS} ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/$R.log; wc -l /tmp/runs/$R/progress.jsonl 2>/dev/null; echo
nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/$R ]; then
  tar czf $OUT/$R.tgz -C /tmp/runs --exclude=$R/actors --exclude=$R/params.pkl $R $R.log rand \
    $(cd /tmp/runs; ls $R.trained done 2>/dev/null)
  ls -la $OUT
fi
