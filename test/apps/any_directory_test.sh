#!/usr/bin/env bash
# The tools work from any directory: run from a fresh folder outside the checkout, with their
# defaults (robot config, policy, scripts) found through pmg's data directory (build/share/pmg).
# Also: pmg_log_export refuses a truncated log (exit 2, warning) after exporting its complete
# events; pmg_calib_dynamics and pmg_calib_zero refuse an unwritable output path before any work;
# no tool prints the KDL root-inertia warning or ANSI colour codes.
#   any_directory_test.sh BIN_DIR STATE_LOG_TOOL
set -uo pipefail
bin="$(cd "${1:?usage: any_directory_test.sh BIN_DIR STATE_LOG_TOOL}" && pwd)"
make_log="$(realpath "${2:?usage: any_directory_test.sh BIN_DIR STATE_LOG_TOOL}")"
data="$bin/../share/pmg"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
unset PMG_DATA_DIR
failures=0

fail() { echo "FAIL $*"; failures=$((failures + 1)); }
# expect RC NAME CMD...: runs CMD, output in $work/NAME.out; checks the exit code and that the output
# has no ANSI escape and no KDL root-inertia warning.
expect() {
  local want=$1 name=$2
  shift 2
  "$@" >"$name.out" 2>&1
  local rc=$?
  if [[ $rc -ne $want ]]; then
    fail "$name: exit code $rc, expected $want: $*"
    sed 's/^/    /' "$name.out" | tail -n 15
    return 1
  fi
  if grep -q $'\e' "$name.out" || grep -q "root link with an inertia" "$name.out"; then
    fail "$name: ANSI colour codes or the KDL root-inertia warning in the output"
    return 1
  fi
  echo "ok   $name"
}
# has NAME TEXT: the output of NAME contains TEXT.
has() { grep -qF -- "$2" "$1.out" || fail "$1: output lacks '$2'"; }

# pmg_log_export: default robot config (29 joints) from the data directory.
"$make_log" run.lcmlog 50 29 || fail "pmg_test_state_log"
expect 0 log_export "$bin/pmg_log_export" --log run.lcmlog --csv run.csv && has log_export "50 PMG_STATE rows"
[[ -f run.csv && $(wc -l <run.csv) -eq 51 ]] || fail "log_export: run.csv should have a header and 50 rows"
# ... a truncated log: the 49 complete events are exported, a warning names the file, exit code 2.
size=$(stat -c %s run.lcmlog)
head -c $((size - 7)) run.lcmlog >cut.lcmlog
expect 2 log_export_truncated "$bin/pmg_log_export" --log cut.lcmlog --csv cut.csv &&
  has log_export_truncated "cut.lcmlog is truncated or corrupt"
[[ -f cut.csv && $(wc -l <cut.csv) -eq 50 ]] || fail "log_export_truncated: cut.csv should have 49 rows"
# ... garbage between events is reported the same way.
{ head -c 300 run.lcmlog; printf 'garbage!'; tail -c +301 run.lcmlog; } >junk.lcmlog
expect 2 log_export_garbage "$bin/pmg_log_export" --log junk.lcmlog --csv junk.csv && has log_export_garbage "bytes between events skipped"
# ... a log of another robot: wrong joint count, nothing exported.
"$make_log" other.lcmlog 5 12 || fail "pmg_test_state_log"
expect 1 log_export_other_robot "$bin/pmg_log_export" --log other.lcmlog --csv other.csv

# pmg_plot_tracking.py: finds pmg_log_export next to itself; --robot is passed on.
if python3 -c "import matplotlib, numpy" 2>/dev/null; then
  expect 0 plot_tracking python3 "$bin/pmg_plot_tracking.py" run.lcmlog run.png --robot "$data/config/robots/g1/g1.yaml"
  [[ -s run.png ]] || fail "plot_tracking: no run.png"
else
  echo "skip plot_tracking (no matplotlib)"
fi

# Tools with the default G1 config of the data directory.
expect 0 policy_check "$bin/pmg_policy_check" --model "$data/config/policies/g1_pmg_policy.onnx" && has policy_check "OK "
expect 0 retarget "$bin/pmg_retarget" "$data/data/motions/deepmimic/humanoid3d_walk.txt" --end 0.2 && has retarget "keypoint error"
expect 0 bus_plan "$bin/pmg_bus_plan" "$data/config/hal/g1_can.yaml" && has bus_plan "accepted"
expect 0 generator_vectors "$bin/pmg_generator_vectors" --ticks 20 --out vectors.json
[[ -s vectors.json ]] || fail "generator_vectors: no vectors.json"
port=$((20000 + ($$ % 1000) * 20))
expect 0 sil "$bin/pmg_sil" --realtime --duration 0.05 --port "$port" && has sil "cycles"
expect 0 gco_eval "$bin/pmg_gco_eval" --vx 0.3 --vy 0 --wz 0 --pitch 0 --roll 0 --height 0 --seconds 1 --warmup 0
expect 0 policy_sil "$bin/pmg_policy_sil" --seeds 1 --duration 0.3 --out policy_sil && has policy_sil "mean over 1 seeds"
[[ -f policy_sil/summary.json ]] || fail "policy_sil: no policy_sil/summary.json"
printf '{}\n' >empty_reality.yaml
expect 0 sim2real "$bin/pmg_sim2real_eval" --policies "p=$data/config/controller/g1_sil_policy.yaml" \
  --realities empty_reality.yaml --duration 0.3 --skip 0 --out sim2real && has sim2real "Dynamic + Zero-point"
[[ -f sim2real/summary.json && -f sim2real/p/sim.csv ]] || fail "sim2real: no sim2real/summary.json or p/sim.csv"
expect 0 controller "$bin/pmg_controller" --config "$data/config/controller/g1_sil.yaml" --duration 0.2 --no-lcm
# Benchmarks, shortened.
expect 0 bench_controller "$bin/bench_controller" --seconds 0.3
expect 0 bench_policy_latency "$bin/bench_policy_latency" --iterations 100
expect 0 gco_tick_bench "$bin/pmg_gco_tick_bench" --ticks 1000
expect 0 bench_motion "$bin/bench_motion" --benchmark_filter=LoadClipLibrary --benchmark_min_time=0.01

# Output paths are checked before any work: the logs named here do not even exist, so an error
# about the output proves it came first.
expect 1 calib_dynamics_bad_report "$bin/pmg_calib_dynamics" --rig "$data/config/bench/dfki_ak80_6.yaml" \
  --train missing_train.csv --heldout missing_heldout.csv --report no_such_dir/report.json &&
  has calib_dynamics_bad_report "no_such_dir/report.json: cannot write"
expect 1 calib_dynamics_bad_plot "$bin/pmg_calib_dynamics" --rig "$data/config/bench/dfki_ak80_6.yaml" \
  --train missing_train.csv --heldout missing_heldout.csv --report report.json --plot no_such_dir/fit.png &&
  has calib_dynamics_bad_plot "no_such_dir/fit.png: cannot write"
[[ ! -e report.json ]] || fail "calib_dynamics_bad_plot: report.json written although the run was refused"
expect 1 calib_zero_bad_out "$bin/pmg_calib_zero" --config "$data/config/robots/g1/g1.yaml" --out no_such_dir/zero.yaml &&
  has calib_zero_bad_out "no_such_dir/zero.yaml: cannot write"

left="$(ls -A | grep -v -E '\.(out|lcmlog|csv|png|json)$|^policy_sil$|^sim2real$|^empty_reality\.yaml$')"
[[ -z "$left" ]] || fail "unexpected files in the working directory: $left"
echo "$failures failures"
[[ $failures -eq 0 ]]
