#!/usr/bin/env bash
# The training's XLA compiles on the GPU machine with glibc's malloc and with tcmalloc preloaded:
# N24m's argv (.whl/argv_ab.txt, no --out), each run stopped after 230 s (past the first 15 M steps).
set -u
mkdir -p /tmp/site /tmp/runs && tar xzf .whl/site.tgz -C /tmp/site || exit 1
export PYTHONPATH=/tmp/site
nproc; python3 -c "import platform; print(platform.libc_ver())"; nvidia-smi -L
LD_PRELOAD=$PWD/.whl/libtcmalloc_minimal.so.4 python3 -c "print('tcmalloc loads')" || exit 1
for a in system tcmalloc; do
  P=""; [ "$a" = tcmalloc ] && P=$PWD/.whl/libtcmalloc_minimal.so.4
  s=$(date +%s)
  LD_PRELOAD=$P TCMALLOC_LARGE_ALLOC_REPORT_THRESHOLD=1099511627776 JAX_LOG_COMPILES=1 \
    JAX_COMPILATION_CACHE_DIR=/tmp/jc_$a timeout 230 python3 $(cat .whl/argv_ab.txt) --out /tmp/runs/ab_$a \
    > $OUT/ab_$a.log 2>&1
  echo "$a rc $? $(( $(date +%s) - s )) s"
  grep -oE "Finished XLA compilation of [^ ]+ in [0-9.]+ sec" $OUT/ab_$a.log | awk '{t += $(NF-1)} END {print "  XLA compile total", t, "s"}'
  grep -E "checkpoint at step|warm-up" $OUT/ab_$a.log | head -4
done
