#!/usr/bin/env bash
# The SIL demo (README's first command), two runs of pmg_controller on the G1 in MuJoCo 2.2:
#  1. bring-up: the robot hangs in the virtual gantry and its legs follow the PMG (+GCO) references
#     through config/commands/demo.yaml (stand, forward 0.5 m/s, turn 0.5 rad/s, combined,
#     backward, stop);
#  2. policy: no gantry, the trained actor drives the legs (PMG on waist and arms) through
#     config/commands/policy_demo.yaml (stand, forward 0.4 m/s, turn 0.4 rad/s, stop).
# Each run records its telemetry as an LCM event log, exported to CSV and plotted (reference vs.
# measured leg joint angles). Output: out/sil_demo/{run,policy_run}.{lcmlog,csv}, *tracking.png,
# summary.txt. Frame strips: scripts/render_sil.sh out/sil_demo/run.lcmlog out/sil_demo/render.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="${1:-out/sil_demo}"
mkdir -p "$out"
: > "$out/summary.txt"
run() {  # name config script
  echo "== $1: $2 with $3" | tee -a "$out/summary.txt"
  build/bin/pmg_controller --config "$2" --script "$3" --no-lcm --log "$out/$1.lcmlog" 2>&1 | tee -a "$out/summary.txt"
  build/bin/pmg_log_export --log "$out/$1.lcmlog" --csv "$out/$1.csv"
  python3 build/bin/pmg_plot_tracking.py "$out/$1.csv" "$out/$1_tracking.png" | tee -a "$out/summary.txt"
}
run run config/controller/g1_sil.yaml config/commands/demo.yaml
run policy_run config/controller/g1_sil_policy.yaml config/commands/policy_demo.yaml
python3 - "$out/policy_run.csv" <<'PY' | tee -a "$out/summary.txt"
import sys
import numpy as np
d = np.genfromtxt(sys.argv[1], delimiter=",", names=True)
print(f"policy run: pelvis travelled x {d['base_x'][-1]:+.2f} m, y {d['base_y'][-1]:+.2f} m; "
      f"lowest pelvis height {d['base_z'].min():.2f} m (fallen below 0.5 m: {'yes' if d['base_z'].min() < 0.5 else 'no'})")
PY
echo "SIL demo done: $out/run_tracking.png, $out/policy_run_tracking.png, event logs in $out/"
