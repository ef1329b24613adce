#!/usr/bin/env bash
# Runs pmg_calib_dynamics on the three real data sets shipped in config/bench/data/ and writes
# reports, plots and actuator blocks into docs/calibration/ (used by docs/calibration.md).
#   scripts/calib_run_real.sh [BUILD_DIR]   (default: build)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="${1:-$root/build}/bin/pmg_calib_dynamics"
out="$root/docs/calibration"
d="$root/config/bench/data"
mkdir -p "$out"
cd "$root"
run() { local name="$1"; shift; echo "== $name"; "$bin" "$@" --report "$out/$name.json" --plot "$out/$name.png" \
          --actuator-out "$out/$name.actuator.yaml" --threads 2 | tee "$out/$name.txt"; }

# Feetech STS3250: train on 3 trajectories, hold out sin_time_square.
s="$d/bam_sts3250"
run bam_sts3250 --rig config/bench/bam_sts3250.yaml \
  --train "$s/2024-10-26_12h23m27.json" "$s/2024-10-26_12h23m42.json" "$s/2024-10-26_12h27m27.json" \
  --heldout "$s/2024-10-26_12h24m55.json"

# DFKI AK80-6 energy shaping (torque control): first 12 s train, last 8 s held out.
e="$d/dfki_ak80_6/energy_shaping/data_measured.csv"
run dfki_ak80_6 --rig config/bench/dfki_ak80_6.yaml --train "$e@0:12" --heldout "$e@12:20"

# Dynamixel XL330: leave-one-gain-out (kp 100/200/400/800 firmware units).
x="$d/bam_xl330"
declare -A files
files[100]="10h28m10 10h28m17 10h28m24 10h28m32"
files[200]="10h28m42 10h28m49 10h28m57 10h29m04"
files[400]="10h29m14 10h29m21 10h29m29 10h29m37"
files[800]="10h29m47 10h29m54 10h30m02 10h30m10"
for held in 100 200 400 800; do
  train=(); ho=()
  for kp in 100 200 400 800; do
    for f in ${files[$kp]}; do
      if [ "$kp" = "$held" ]; then ho+=("$x/2026-01-15_$f.json"); else train+=("$x/2026-01-15_$f.json"); fi
    done
  done
  run "bam_xl330_heldout_kp$held" --rig config/bench/bam_xl330.yaml --train "${train[@]}" --heldout "${ho[@]}"
done
