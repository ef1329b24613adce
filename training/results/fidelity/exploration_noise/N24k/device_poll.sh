#!/bin/bash
# poll.sh SECONDS: wait up to SECONDS (returns early when the job is done), print progress, copy what exists into $OUT
end=$(( $(date +%s) + $1 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/N24k.log; wc -l /tmp/runs/N24k/progress.jsonl 2>/dev/null; tail -c 600 /tmp/runs/N24k/progress.jsonl 2>/dev/null; echo; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/N24k ]; then tar czf $OUT/N24k.tgz -C /tmp/runs --exclude=rand/N24k.npz --exclude=N24k/actors --exclude=N24k/params.pkl N24k N24k.log rand $(cd /tmp/runs; ls mjx_crouched_backward_N24k.txt N24k.trained done 2>/dev/null); ls -la $OUT; du -sh $OUT/*; fi
