#!/bin/bash
# The lean while side-stepping with the posture feedback's roll bound at +-0.3 rad instead of the default's +-0.2
# (docs/controller.md "The lean while side-stepping"): posture walks, seeds 120-125 (the battery's first six), both
# configs side by side. Run from the repository root after scripts/build.sh; keeps the summaries, deletes the CSVs
# after the figure.
set -e
cd "$(dirname "$0")/../../../.."
D=training/results/fidelity/posture_envelope/roll_0.3
P=training/results/fidelity/crouched/posture_walks.yaml
C=config/controller/zz_roll03.yaml   # a temporary copy next to the default, so that its relative paths resolve
sed -e 's/^  envelope_min: \[-0.3, -0.2\]/  envelope_min: [-0.3, -0.3]/' -e 's/^  envelope_max: \[0.5, 0.2\]/  envelope_max: [0.5, 0.3]/' \
  config/controller/g1_sil_policy.yaml > $C
export PMG_MJCF_CACHE_DIR=build/mjcf_cache
build/bin/pmg_policy_sil --commands $P --seeds 6 --first-seed 120 --restart-after-fall --out /tmp/roll/base &
build/bin/pmg_policy_sil --controller $C --commands $P --seeds 6 --first-seed 120 --restart-after-fall --out /tmp/roll/r03
wait
rm -f $C
python3 scripts/plot_stop.py --run "roll bound ±0.2 (default)=/tmp/roll/base@120" --run "roll bound ±0.3=/tmp/roll/r03@120" \
  --t0 83 --t1 90 --axis vy --title "lean -0.2 rad while side-stepping -0.4 m/s (posture walks, seed 120)" \
  --out docs/img/controller_roll_bound_lean_side.png
cp /tmp/roll/base/summary.json $D/default_seeds120-125_summary.json
cp /tmp/roll/r03/summary.json $D/roll0.3_seeds120-125_summary.json
python3 scripts/segment_band.py $D/default_seeds120-125_summary.json > $D/base_band.txt
python3 scripts/segment_band.py $D/roll0.3_seeds120-125_summary.json > $D/r03_band.txt
