#!/usr/bin/env bash
# The Table II policies shipped for issue 15 (config/controller/g1_sil_table2_*.yaml, trained on the
# device from one checkpoint, 40 M steps each) on the robot they were calibrated on: the hidden reality
# `pmg_reality_draw --seed 1 --joints 4` (drawn here, as scripts/calib_reality_check.py draws it; the
# tools and configs never read it), the paper's protocol (config/policies/eval_sim2real.yaml).
# Asserts the issue's target: "Dynamic + Zero-point" has the lowest Motion Imitation Error and the
# lowest Sim-to-Real Error of the four, its Sim-to-Real Error is at most 0.55 x Baseline's, and
# Baseline, Dynamic Calibration and Dynamic + Zero-point do not fall. (Physically Informed Gains falls
# after 40 M steps: docs/calibration.md says why; its row is reported, not asserted.)
#   table2_trained_test.sh BIN_DIR SOURCE_DIR
set -euo pipefail
bin="${1:?usage: table2_trained_test.sh BIN_DIR SOURCE_DIR}"
src="$(cd "${2:?usage: table2_trained_test.sh BIN_DIR SOURCE_DIR}" && pwd)"
d="$(mktemp -d)"
trap 'rm -rf "$d"' EXIT
"$bin/pmg_reality_draw" --seed 1 --joints 4 --out "$d/reality.yaml" >/dev/null
c="$src/config/controller"
rc=0
"$bin/pmg_sim2real_eval" --realities "$d/reality.yaml" --out "$d/out" --policies \
  "Baseline=$c/g1_sil_table2_baseline.yaml,Physically Informed Gains=$c/g1_sil_table2_pig.yaml,Dynamic Calibration=$c/g1_sil_table2_dynamic.yaml,Dynamic + Zero-point=$c/g1_sil_table2_dynamic_zero.yaml" \
  >"$d/log.txt" 2>&1 || rc=$?
cat "$d/log.txt" | tail -n 9
[ "$rc" = 0 ] || [ "$rc" = 3 ] || { echo "FAIL: pmg_sim2real_eval exit $rc"; exit 1; }
python3 - "$d/out/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["policies"]
mie = {k: v["motion_imitation_error_rad"] for k, v in s.items()}
s2r = {k: v["sim_to_real_error_rad"] for k, v in s.items()}
fell = {k: any(r["fell"] for r in v["per_reality"]) for k, v in s.items()}
dz, base = "Dynamic + Zero-point", "Baseline"
fail = []
if min(mie, key=mie.get) != dz:
    fail.append(f"Motion Imitation Error: {dz} not lowest: {mie}")
if min(s2r, key=s2r.get) != dz:
    fail.append(f"Sim-to-Real Error: {dz} not lowest: {s2r}")
if not s2r[dz] <= 0.55 * s2r[base]:
    fail.append(f"Sim-to-Real Error {s2r[dz]:.4f} > 0.55 x Baseline's {s2r[base]:.4f}")
for k in (base, "Dynamic Calibration", dz):
    if fell[k]:
        fail.append(f"{k} fell")
print("\n".join("FAIL: " + f for f in fail) if fail else
      f"Table II (trained, robot s1): {dz} lowest on both columns, S2R {s2r[dz]:.4f} = "
      f"{s2r[dz] / s2r[base]:.2f} x Baseline's {s2r[base]:.4f}")
sys.exit(1 if fail else 0)
PY
