#!/bin/bash
# poll.sh SECONDS: wait up to SECONDS (returns early when the job is done), print progress, copy what exists into $OUT
end=$(( $(date +%s) + $1 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/N24h.log; wc -l /tmp/runs/N24h/progress.jsonl 2>/dev/null; tail -c 600 /tmp/runs/N24h/progress.jsonl 2>/dev/null; echo; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/N24h ]; then tar czf $OUT/N24h.tgz -C /tmp/runs --exclude=rand/N24h.npz --exclude=N24h/actors --exclude=N24h/params.pkl N24h N24h.log rand $(cd /tmp/runs; ls mjx_crouched_backward_N24h.txt N24h.trained done 2>/dev/null); ls -la $OUT; du -sh $OUT/*; fi
