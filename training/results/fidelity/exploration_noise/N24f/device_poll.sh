#!/bin/bash
# poll.sh SECONDS: wait up to SECONDS (returns early when the job is done), print progress, copy what exists into $OUT
end=$(( $(date +%s) + $1 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/N24f.log; wc -l /tmp/runs/N24f/progress.jsonl 2>/dev/null; tail -c 600 /tmp/runs/N24f/progress.jsonl 2>/dev/null; echo; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/N24f ]; then tar czf $OUT/N24f.tgz -C /tmp/runs --exclude=N24f/actors --exclude=N24f/params.pkl N24f N24f.log rand $(cd /tmp/runs; ls mjx_crouched_backward_N24f.txt N24f.trained done 2>/dev/null); ls -la $OUT; fi
