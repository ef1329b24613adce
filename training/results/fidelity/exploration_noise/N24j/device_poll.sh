#!/bin/bash
# poll.sh SECONDS: wait up to SECONDS (returns early when the job is done), print progress, copy what exists into $OUT
end=$(( $(date +%s) + $1 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/N24j.log; wc -l /tmp/runs/N24j/progress.jsonl 2>/dev/null; tail -c 600 /tmp/runs/N24j/progress.jsonl 2>/dev/null; echo; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/N24j ]; then tar czf $OUT/N24j.tgz -C /tmp/runs --exclude=rand/N24j.npz --exclude=N24j/actors --exclude=N24j/params.pkl N24j N24j.log rand $(cd /tmp/runs; ls mjx_crouched_backward_N24j.txt N24j.trained done 2>/dev/null); ls -la $OUT; du -sh $OUT/*; fi
