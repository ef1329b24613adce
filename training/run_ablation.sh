#!/usr/bin/env bash
# Trains Table I configurations concurrently, one process per GPU, on the device machine.
#   training/run_ablation.sh start OUT MINUTES TIMESTEPS JOB [JOB ...]    JOB = mode:gpu:seed
#   training/run_ablation.sh collect OUT DEST                             checkpoints + logs -> DEST/*.tgz
# `start` unpacks .whl/site.tgz (make_device_site.sh), launches every job in its own session
# (setsid: it outlives the device command that started it, so later commands can poll it) under
# `timeout MINUTES`, and returns. Each job writes OUT/<mode>_s<seed>/ (train_pmg.py: progress.jsonl,
# params.pkl + actor.npz at every evaluation, g1_pmg_policy.onnx when it reaches TIMESTEPS) and
# OUT/<mode>_s<seed>.log. `collect` exports every job's latest actor.npz to ONNX (export_onnx.py) and
# packs logs, progress, params and ONNX into DEST/runs.tgz (the device tool returns files <= 16 MiB).
set -uo pipefail
cmd=$1; shift
case "$cmd" in
  start)
    out=$1 minutes=$2 steps=$3; shift 3
    mkdir -p /tmp/site "$out" && tar xzf .whl/site.tgz -C /tmp/site || exit 1
    export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false MUJOCO_GL=disable
    for job in "$@"; do
      IFS=: read -r mode gpu seed <<<"$job"
      name=${mode}_s${seed}
      CUDA_VISIBLE_DEVICES=$gpu setsid timeout "${minutes}m" python3 training/train_pmg.py --out "$out/$name" \
        --mode "$mode" --seed "$seed" --timesteps "$steps" --num-evals "${NUM_EVALS:-14}" >"$out/$name.log" 2>&1 < /dev/null &
      echo "started $name on GPU $gpu"
    done
    ;;
  collect)
    out=$1 dest=$2
    export PYTHONPATH=/tmp/site
    for d in "$out"/*/; do
      [ -f "$d/actor.npz" ] && python3 training/export_onnx.py "$d/actor.npz" "$d/latest_policy.onnx" >/dev/null
    done
    tar czf "$dest/runs.tgz" -C "$out" . && ls -la "$dest"
    ;;
  *) echo "usage: $0 start|collect ..." >&2; exit 2 ;;
esac
