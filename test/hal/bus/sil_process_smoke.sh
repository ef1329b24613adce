#!/usr/bin/env bash
# pmg_controller against the pmg_sil process through the real bus code (UDP CAN, MIT codec,
# CanBackend) with the HAL safety supervisor (always on): (1) the demo script runs clean and ends active;
# (2) with 2 % dropped, late, duplicated and corrupted replies it still ends active (the HAL holds
# a missing reply within the watchdog); (3) with a motor that stops replying after 4 s the HAL
# latches damping and names the joint; (4) without pmg_sil the run never becomes active, names the
# cause and exits 4.
# Usage: sil_process_smoke.sh <pmg_sil> <pmg_controller>   (run from the repository root)
set -u
sil="$1"
ctl="$2"
port=$((40000 + ($$ % 500) * 20))
out="$(mktemp -d)"
trap 'kill "$sil_pid" 2>/dev/null; rm -rf "$out"' EXIT

run() {  # run <name> <sil args...>
  local name="$1"
  shift
  "$sil" --port "$port" "$@" > "$out/$name.sil.log" 2>&1 &
  sil_pid=$!
  sleep 1
  "$ctl" --config config/controller/g1_sil.yaml --script config/commands/demo.yaml --no-lcm \
    --can-plan config/hal/g1_can.yaml --can-port "$port" > "$out/$name.ctl.log" 2>&1
  local rc=$?
  kill "$sil_pid" 2>/dev/null
  wait "$sil_pid" 2>/dev/null
  port=$((port + 14))
  return $rc
}

fail=0
if run clean; then
  grep -q "final mode: active; fault: none" "$out/clean.ctl.log" || { echo "clean run: HAL not active"; fail=1; }
else
  echo "clean run failed:"; cat "$out/clean.ctl.log"; fail=1
fi
if run lossy --drop 0.02 --late 0.02 --dup 0.02 --corrupt 0.02 --faults-after 2; then
  grep -q "final mode: active; fault: none" "$out/lossy.ctl.log" || { echo "lossy run: HAL not active"; fail=1; }
else
  echo "lossy run failed:"; cat "$out/lossy.ctl.log"; cat "$out/lossy.sil.log"; fail=1
fi
run silent --silent-joint 3 --faults-after 4
rc=$?
[ "$rc" -eq 3 ] || { echo "silent motor: expected exit 3 (damping), got $rc"; fail=1; }
grep -q "final mode: damping; fault: motor reply timeout (joint 3," "$out/silent.ctl.log" ||
  { echo "silent motor: damping cause not recorded"; cat "$out/silent.ctl.log"; fail=1; }
# No pmg_sil at all: the run never becomes active, says why and exits 4.
"$ctl" --config config/controller/g1_sil.yaml --realtime --duration 1 --no-lcm --can-plan config/hal/g1_can.yaml \
  --can-port "$port" > "$out/nosil.ctl.log" 2>&1
rc=$?
[ "$rc" -eq 4 ] || { echo "no pmg_sil: expected exit 4, got $rc"; cat "$out/nosil.ctl.log"; fail=1; }
grep -q "no motor replied in" "$out/nosil.ctl.log" || { echo "no pmg_sil: cause not named"; cat "$out/nosil.ctl.log"; fail=1; }
[ $fail -eq 0 ] && echo "pmg_controller <-> pmg_sil over UDP CAN: clean and lossy runs active, silent motor -> damping (joint 3)"
exit $fail
