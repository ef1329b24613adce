#!/bin/bash
# poll.sh SECONDS: wait up to SECONDS (returns early when the job is done), print progress, copy what exists into $OUT
end=$(( $(date +%s) + $1 ))
while [ $(date +%s) -lt $end ] && [ ! -f /tmp/runs/done ]; do sleep 10; done
date; tail -n 4 /tmp/runs/N24g.log; wc -l /tmp/runs/N24g/progress.jsonl 2>/dev/null; tail -c 600 /tmp/runs/N24g/progress.jsonl 2>/dev/null; echo; nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv
ls /tmp/runs /tmp/runs/rand
if [ -d /tmp/runs/N24g ]; then tar czf $OUT/N24g.tgz -C /tmp/runs --exclude=rand/N24g.npz --exclude=N24g/actors --exclude=N24g/params.pkl N24g N24g.log rand $(cd /tmp/runs; ls mjx_crouched_backward_N24g.txt N24g.trained done 2>/dev/null); ls -la $OUT; du -sh $OUT/*; fi
