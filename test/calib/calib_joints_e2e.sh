#!/bin/sh
# End-to-end pmg_calib_joints through the motor bus (issue 15): pmg_sil plays a robot whose left hip
# yaw driver is 25 % stiffer than the model (REALITY.yaml, hidden from the tool: separate process,
# CAN frames over UDP); pmg_calib_joints calibrates three leg joints through the HAL stack and
# must name pd_gain on the hip yaw (kp_scale 1.25 within 0.05, the bench tests' tolerance, with an
# uncertainty in (0, 0.05)) and nothing on the knee and ankle; the calibrated robot config it writes
# (the block and its `actuator_uncertainty:`) must load in the SIL.
#   calib_joints_e2e.sh BIN_DIR SOURCE_DIR
set -eu
bin=$1 src=$2
d=$(mktemp -d)
trap 'kill $sil 2>/dev/null || true; rm -rf "$d"' EXIT
printf 'joints: {left_hip_yaw_joint: {kp_scale: 1.25}}\n' > "$d/reality.yaml"
sed -e "s#: \.\./#: $src/config/#" -e "s/^  mode: realtime/  mode: lockstep/" -e "s/udp_port: 47000/udp_port: 47420/" \
    "$src/config/controller/g1_sil_can.yaml" > "$d/controller.yaml"
"$bin/pmg_sil" --reality "$d/reality.yaml" --port 47420 > "$d/sil.log" 2>&1 &
sil=$!
sleep 0.5
"$bin/pmg_calib_joints" --config "$d/controller.yaml" \
    --joints left_hip_yaw_joint,left_knee_joint,left_ankle_pitch_joint \
    --out "$d/calibrated.yaml" --report "$d/report.json" --threads 2 | tee "$d/out.txt"
python3 - "$d/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
j = r["joints"]
fail = []
e = j["left_hip_yaw_joint"]["causes"]
if not e or e[0]["name"] != "pd_gain" or abs(e[0]["params"]["kp_scale"] - 1.25) > 0.05:
    fail.append(f"left_hip_yaw_joint: expected pd_gain kp_scale 1.25 +- 0.05 first, got {e}")
elif not 0 < e[0].get("uncertainty", {}).get("kp_scale", -1) < 0.05:
    fail.append(f"left_hip_yaw_joint: expected an uncertainty of kp_scale in (0, 0.05), got {e[0].get('uncertainty')}")
for name in ("left_knee_joint", "left_ankle_pitch_joint"):
    if j[name]["causes"]:
        fail.append(f"{name}: expected nothing named, got {j[name]['causes']}")
if r.get("bus_latency_cycles") != 1:
    fail.append(f"bus latency {r.get('bus_latency_cycles')} cycles, expected 1 (MIT mode over UDP in lockstep)")
print("\n".join(fail) if fail else "pmg_calib_joints: verdicts as hidden")
sys.exit(1 if fail else 0)
PY
kill $sil 2>/dev/null || true
wait $sil 2>/dev/null || true
grep -q "left_hip_yaw_joint.*actuator: {[^}]*}, actuator_uncertainty: {kp_scale: " "$d/calibrated.yaml"
# (a port block of its own: one SIL takes 14 ports from its base)
"$bin/pmg_sil" --robot "$d/calibrated.yaml" --realtime --duration 0.05 --port 47460 > "$d/sil2.log" 2>&1 || { cat "$d/sil2.log"; exit 1; }
