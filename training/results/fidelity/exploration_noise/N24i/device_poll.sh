#!/bin/bash
# poll.sh SECONDS: wait up to SECONDS (returns early when the job is done), print progress, copy what exists into $OUT
end=$(( $(date +%s) + $1 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/N24i.log; wc -l /tmp/runs/N24i/progress.jsonl 2>/dev/null; tail -c 600 /tmp/runs/N24i/progress.jsonl 2>/dev/null; echo; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/N24i ]; then tar czf $OUT/N24i.tgz -C /tmp/runs --exclude=rand/N24i.npz --exclude=N24i/actors --exclude=N24i/params.pkl N24i N24i.log rand $(cd /tmp/runs; ls mjx_crouched_backward_N24i.txt N24i.trained done 2>/dev/null); ls -la $OUT; du -sh $OUT/*; fi
