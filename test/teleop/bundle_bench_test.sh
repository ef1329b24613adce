#!/usr/bin/env bash
# scripts/bundle_bench.sh: the bundle (the bench with its own libraries and loader) runs a box trial
# from another folder and judges it exactly as the build does (the bench is deterministic per seed).
#   bundle_bench_test.sh BIN_DIR   (run from the source root)
set -euo pipefail
bin_dir=$1
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
XZ_OPT=-0 scripts/bundle_bench.sh "$bin_dir/pmg_teleop_bench" "$d/bench.txz"
mkdir "$d/there" && tar -C "$d/there" -xJf "$d/bench.txz"
n=$(ls "$d/there/bundle/lib" | wc -l)
[[ -x "$d/there/bundle/run.sh" && -e "$d/there/bundle/lib/libmujoco.so.2.2.2" && -e "$d/there/bundle/lib/libc.so.6" ]] ||
  { echo "FAIL: the bundle lacks run.sh, MuJoCo or glibc ($n libraries)"; exit 1; }
(cd "$d" && PMG_DATA_DIR="$OLDPWD" env -u LD_LIBRARY_PATH there/bundle/run.sh --task box --trials 1 --seed 1 --no-figures --out "$d/b" > "$d/b.log" 2>&1) ||
  { echo "FAIL: the bundle's bench failed:"; tail -5 "$d/b.log"; exit 1; }
"$bin_dir/pmg_teleop_bench" --task box --trials 1 --seed 1 --no-figures --out "$d/a" > "$d/a.log" 2>&1
python3 - "$d/a/summary.json" "$d/b/summary.json" <<'PY'
import json, sys
a, b = (json.load(open(p))["trial_results"][0] for p in sys.argv[1:3])
keys = ("success", "measure", "fell", "regrabs", "seconds", "detail")
diff = [k for k in keys if a[k] != b[k]]
if diff:
    print("FAIL: the bundle's trial differs from the build's in " + ", ".join(f"{k}: {a[k]!r} / {b[k]!r}" for k in diff))
    sys.exit(1)
print(f"bundle: the trial judged as the build judges it ({'success' if a['success'] else 'failure'}, lift {a['measure']:.3f} m)")
PY
