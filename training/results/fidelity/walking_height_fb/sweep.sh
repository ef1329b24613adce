#!/bin/bash
# sweep.sh CONFIG COMMANDS OUT: 72 seeds (0-71) of pmg_policy_sil, 12 per run, 2 runs at a time; commands.txt lists them.
set -e
CFG=$1; CMD=$2; OUT=$3
mkdir -p $OUT
for s in 0 12 24 36 48 60; do
  d=$OUT/seeds$s-$((s+11)); mkdir -p $d
  echo "build/bin/pmg_policy_sil --controller $CFG --commands $CMD --seeds 12 --first-seed $s --restart-after-fall --out $d > $d/log.txt 2>&1"
done > $OUT/commands.txt
xargs -P 2 -I{} sh -c "{}" < $OUT/commands.txt || true  # a run with a fall exits non-zero
grep -h 'FELL' $OUT/seeds*/log.txt | sed 's/ | LinVel.*fall:/ fall:/' || true
echo "runs with a fall: $(cat $OUT/seeds*/log.txt | grep -c 'FELL') of 72"
