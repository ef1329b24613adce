#!/usr/bin/env bash
# Fine-tunes several policy variants from one checkpoint, side by side on the device machine (the
# Table II policies, issue 15: trained alike = same start, same steps, same rewards and PPO
# settings; only the gains / actuator model differ).
#   training/run_finetune.sh start OUT MINUTES TIMESTEPS RESTORE 'NAME|GPU|EXTRA FLAGS' ...
#   training/run_finetune.sh status OUT
#   training/run_finetune.sh collect OUT DEST        actors, progress, configs, logs -> DEST/runs.tgz,
#                                                    params.pkl -> DEST/params_NAME.pkl (export the ONNX
#                                                    afterwards with export_onnx.py [--robot ...])
# `start` unpacks .whl/site.tgz (make_device_site.sh), launches every job in its own session
# (setsid: it outlives the device command that started it) under `timeout MINUTES`, and returns.
# Each job writes OUT/NAME/ (train_pmg.py: progress.jsonl, params.pkl + actor.npz at every
# evaluation, the ONNX when it reaches TIMESTEPS) and OUT/NAME.log. Several jobs may share a GPU.
set -uo pipefail
cmd=$1; shift
case "$cmd" in
  start)
    out=$1 minutes=$2 steps=$3 restore=$4; shift 4
    mkdir -p /tmp/site "$out" && tar xzf .whl/site.tgz -C /tmp/site || exit 1
    export PYTHONPATH=/tmp/site PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false MUJOCO_GL=disable
    for job in "$@"; do
      IFS='|' read -r name gpu extra <<<"$job"
      # shellcheck disable=SC2086  # EXTRA FLAGS are split on purpose
      CUDA_VISIBLE_DEVICES=$gpu setsid timeout "${minutes}m" python3 training/train_pmg.py --out "$out/$name" \
        --mode pmg_gco --restore "$restore" --timesteps "$steps" --num-evals "${NUM_EVALS:-5}" $extra \
        >"$out/$name.log" 2>&1 < /dev/null &
      echo "started $name on GPU $gpu: $extra"
    done
    ;;
  status)
    out=$1
    for l in "$out"/*.log; do echo "== $l"; grep -E "step|eval|reward|Error|error" "$l" | tail -3; done
    nvidia-smi --query-gpu=index,utilization.gpu,memory.used --format=csv,noheader
    ;;
  collect)
    out=$1 dest=$2
    export PYTHONPATH=/tmp/site
    tar czf "$dest/runs.tgz" --exclude='*.pkl' -C "$out" . && ls -la "$dest"
    for d in "$out"/*/; do n=$(basename "$d"); [ -f "$d/params.pkl" ] && cp "$d/params.pkl" "$dest/params_$n.pkl"; done
    ;;
  *) echo "usage: $0 start|status|collect ..." >&2; exit 2 ;;
esac
