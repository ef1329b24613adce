#!/usr/bin/env bash
# pmg_sim2real_eval (the paper's Table II in the SIL) with the shipped policy config
# config/controller/g1_sil_policy_consistent.yaml on a short script (stand 1.5 s, forward 0.4 m/s):
#  (a) an empty reality: the "real" rollout is the simulator's, bit for bit: Sim-to-Real Error == 0;
#  (b) a strong hidden effect (knees kp x 0.7, +0.05 rad encoder offset on the left hip pitch):
#      Sim-to-Real Error clearly > 0, Motion Imitation Error above (a)'s;
#  (c) an offset-only reality (the same 0.05 rad): a robot config carrying the matching
#      zero_offsets (the HAL subtracts them; its simulator reads them too) lowers the error;
#  (d) bad input: an unknown key of a reality, a malformed --policies entry -> exit 1, file and key named;
#  plus the summary's shape, the CSVs and (with matplotlib) scripts/plot_sim2real.py.
#   sim2real_test.sh EXE SOURCE_DIR
set -euo pipefail
exe="${1:?usage: sim2real_test.sh EXE SOURCE_DIR}"
src="$(cd "${2:?usage: sim2real_test.sh EXE SOURCE_DIR}" && pwd)"
d="$(mktemp -d)"
trap 'rm -rf "$d"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

cat >"$d/cmd.yaml" <<'EOF'
ramp: 0.5
duration: 4.0
segments:
  - {name: stand,   t: 0.0, vx: 0.0, vy: 0.0, wz: 0.0, pitch: 0.0, roll: 0.0, height: 0.78}
  - {name: forward, t: 1.5, vx: 0.4, vy: 0.0, wz: 0.0, pitch: 0.0, roll: 0.0, height: 0.78}
EOF
printf '{}\n' >"$d/empty.yaml"
cat >"$d/strong.yaml" <<'EOF'
joints:
  left_knee_joint: {kp_scale: 0.7}
  right_knee_joint: {kp_scale: 0.7}
zero_offsets: {left_hip_pitch_joint: 0.05}
EOF
printf 'zero_offsets: {left_hip_pitch_joint: 0.05}\n' >"$d/offset.yaml"
ctrl="$src/config/controller/g1_sil_policy_consistent.yaml"
# The same robot with the matching zero_offsets, and a controller config that runs on it.
sed -e "s#^\(  urdf: \)#\1$src/config/robots/g1/#" -e "s#^\(  mjcf: \)#\1$src/config/robots/g1/#" \
  "$src/config/robots/g1/g1.yaml" >"$d/g1_zero.yaml"
printf 'zero_offsets: {left_hip_pitch_joint: 0.05}\n' >>"$d/g1_zero.yaml"
sed -e "s#^robot: .*#robot: $d/g1_zero.yaml#" -e "s#\.\./#$src/config/controller/../#g" "$ctrl" >"$d/ctrl_zero.yaml"

# (a), (b)
"$exe" --policies "shipped=$ctrl" --realities "$d/empty.yaml,$d/strong.yaml" --commands "$d/cmd.yaml" --out "$d/ab" \
  >"$d/ab.txt" 2>&1 || { cat "$d/ab.txt"; fail "(a)/(b): exit code $?"; }
cat "$d/ab.txt"
grep -q "Dynamic + Zero-point" "$d/ab.txt" || fail "the table lacks the paper's rows"
# (c)
"$exe" --policies "plain=$ctrl,zero-point=$d/ctrl_zero.yaml" --realities "$d/offset.yaml" --commands "$d/cmd.yaml" \
  --out "$d/c" >"$d/c.txt" 2>&1 || { cat "$d/c.txt"; fail "(c): exit code $?"; }
cat "$d/c.txt"

python3 - "$d" <<'EOF'
import csv, json, math, os, sys
d = sys.argv[1]
ab = json.load(open(os.path.join(d, "ab", "summary.json")))
c = json.load(open(os.path.join(d, "c", "summary.json")))
def check(cond, msg):
    if not cond:
        sys.exit("FAIL: " + msg)
for k in ("protocol", "realities", "policies", "paper"):
    check(k in ab, f"summary.json lacks '{k}'")
check(ab["paper"]["Dynamic + Zero-point"] == [0.0562, 0.0414], "paper values")
check(len(ab["protocol"]["leg_joints"]) == 12, "12 leg joints")
p = ab["policies"]["shipped"]
(a, b) = p["per_reality"]
for r in (a, b):
    for k in ("reality", "motion_imitation_error_rad", "sim_to_real_error_rad", "fell"):
        check(k in r, f"per_reality lacks '{k}'")
    check(not r["fell"], f"fell on {r['reality']}")
    rows = list(csv.DictReader(open(os.path.join(d, "ab", r["csv"]))))
    check(len(rows) >= 390, f"{r['csv']}: {len(rows)} rows, expected a 4 s run at 100 Hz")
    check("qsim_left_knee_joint" in rows[0] and "qref_left_knee_joint" in rows[0], f"{r['csv']}: columns")
check(a["sim_to_real_error_rad"] == 0.0, f"(a) empty reality: Sim-to-Real Error {a['sim_to_real_error_rad']}, expected exactly 0")
check(abs(a["motion_imitation_error_rad"] - p["simulator"]["motion_imitation_error_rad"]) == 0.0,
      "(a) the real rollout's Motion Imitation Error differs from the simulator's")
check(0.0 < a["motion_imitation_error_rad"] < 0.1, f"(a) Motion Imitation Error {a['motion_imitation_error_rad']}")
check(b["sim_to_real_error_rad"] > 0.01, f"(b) strong reality: Sim-to-Real Error {b['sim_to_real_error_rad']}, expected > 0.01")
check(b["motion_imitation_error_rad"] > a["motion_imitation_error_rad"], "(b) Motion Imitation Error not above (a)'s")
check(abs(p["sim_to_real_error_rad"] - 0.5 * b["sim_to_real_error_rad"]) < 1e-12, "mean over realities")
plain = c["policies"]["plain"]["per_reality"][0]["sim_to_real_error_rad"]
zero = c["policies"]["zero-point"]["per_reality"][0]["sim_to_real_error_rad"]
check(plain > 0.005, f"(c) offset-only reality, no zero offsets: Sim-to-Real Error {plain}, expected > 0.005")
check(zero < 0.25 * plain, f"(c) with the matching zero_offsets: Sim-to-Real Error {zero}, expected < 0.25 x {plain}")
print(f"ok: (a) S2R {a['sim_to_real_error_rad']}, MIE {a['motion_imitation_error_rad']:.4f}; "
      f"(b) S2R {b['sim_to_real_error_rad']:.4f}, MIE {b['motion_imitation_error_rad']:.4f}; "
      f"(c) S2R without / with zero_offsets {plain:.4f} / {zero:.4g}")
EOF

# (d) bad input: exit 1, the file and the key named.
printf 'joints: {left_knee_joint: {kp_scale: 0.9}}\nzero_offset: {left_knee_joint: 0.01}\n' >"$d/bad.yaml"
set +e
"$exe" --policies "shipped=$ctrl" --realities "$d/bad.yaml" --commands "$d/cmd.yaml" --out "$d/bad" >"$d/bad.txt" 2>&1
rc=$?
set -e
[[ $rc -eq 1 ]] || { cat "$d/bad.txt"; fail "unknown reality key: exit code $rc, expected 1"; }
grep -q "bad.yaml" "$d/bad.txt" && grep -q "zero_offset" "$d/bad.txt" || { cat "$d/bad.txt"; fail "unknown reality key not named"; }
set +e
"$exe" --policies "$ctrl" --realities "$d/empty.yaml" --out "$d/bad2" >"$d/bad2.txt" 2>&1
rc=$?
set -e
[[ $rc -eq 1 ]] && grep -q "expected NAME=CONTROLLER.yaml" "$d/bad2.txt" || { cat "$d/bad2.txt"; fail "--policies without a name: exit code $rc"; }

if python3 -c "import matplotlib" 2>/dev/null; then
  python3 "$src/scripts/plot_sim2real.py" "$d/ab" >/dev/null && [[ -s "$d/ab/sim2real.png" ]] || fail "plot_sim2real.py"
else
  echo "skip plot_sim2real.py (no matplotlib)"
fi
echo "sim2real_test: all checks passed"
