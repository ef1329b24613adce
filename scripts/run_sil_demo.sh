#!/usr/bin/env bash
# The SIL demo: pmg_controller drives the G1 (hanging in the virtual gantry) in MuJoCo 2.2 through
# the scripted command sequence config/commands/demo.yaml (stand, forward 0.5 m/s, turn 0.5 rad/s,
# combined, backward, stop), records the telemetry as an LCM event log, exports it to CSV and
# plots reference vs. measured leg joint angles.
# Output: out/sil_demo/{run.lcmlog, run.csv, tracking.png, summary.txt}
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="${1:-out/sil_demo}"
mkdir -p "$out"
build/bin/pmg_controller --config config/controller/g1_sil.yaml --script config/commands/demo.yaml \
  --log "$out/run.lcmlog" | tee "$out/summary.txt"
build/bin/pmg_log_export --log "$out/run.lcmlog" --csv "$out/run.csv"
python3 build/bin/pmg_plot_tracking.py "$out/run.lcmlog" "$out/tracking.png" | tee -a "$out/summary.txt"
echo "SIL demo done: $out/tracking.png, $out/run.lcmlog (lcm-logplayer / lcm-spy compatible)"
