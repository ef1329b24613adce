#!/bin/bash
# F13 against H10a (the default) on held-out seeds 5000 and up, run once after F13 was chosen on the battery's seeds
# (action_range/README.md "F13"). Each line of jobs.txt: NAME MODEL SCHEDULE FIRST_SEED SEEDS; the default config
# with --model; 2 at a time; per-tick CSVs deleted. Writes NAME/summary.json, NAME.log and NAME_band.txt here, or with
# DIR (a folder beside this one holding its own jobs.txt, e.g. heldout_settle) there.
#   training/results/fidelity/action_range/heldout_F13/run.sh [DIR]   (from the repository root)
cd "$(dirname "$0")/../../../../.."
export H=training/results/fidelity/action_range/${1:-heldout_F13}
job() {  # NAME MODEL SCHEDULE FIRST SEEDS
  local O=$H/$1
  build/bin/pmg_policy_sil --controller config/controller/g1_sil_policy.yaml --model $2 --commands $3 \
    --seeds $5 --first-seed $4 --restart-after-fall --out $O > $O.log 2>&1
  find $O -name "*.csv" -delete
  python3 scripts/segment_band.py $O/summary.json > ${O}_band.txt 2>&1
}
export -f job
grep -v '^#' $H/jobs.txt | xargs -P 2 -L 1 bash -c 'job "$@"' _
