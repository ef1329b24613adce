#!/usr/bin/env bash
# Every executable in BIN_DIR (build/bin, not bin/tests) answers --help: exit code 0, usage text on
# stdout or stderr, and no side effect: run from a fresh empty folder, that folder stays empty (no
# log, no CSV, no MUJOCO_LOG.TXT) and no benchmark or simulation starts (20 s limit per tool).
#   help_test.sh BIN_DIR
set -uo pipefail
bin_dir="$(cd "${1:?usage: help_test.sh BIN_DIR}" && pwd)"
failures=0 checked=0
for exe in "$bin_dir"/*; do
  [[ -f "$exe" && -x "$exe" ]] || continue
  name="$(basename "$exe")"
  work="$(mktemp -d)"
  out="$(cd "$work" && env -u PMG_DATA_DIR timeout 20 "$exe" --help 2>&1)"
  rc=$?
  left="$(ls -A "$work")"
  rm -rf "$work"
  checked=$((checked + 1))
  if [[ $rc -ne 0 ]]; then
    echo "FAIL $name --help: exit code $rc${out:+: $(head -c 300 <<<"$out")}"
    failures=$((failures + 1))
  elif [[ -z "${out//[[:space:]]/}" ]]; then
    echo "FAIL $name --help: no usage text"
    failures=$((failures + 1))
  elif [[ -n "$left" ]]; then
    echo "FAIL $name --help: wrote into the working directory: $left"
    failures=$((failures + 1))
  else
    echo "ok   $name --help ($(wc -l <<<"$out") lines)"
  fi
done
if [[ $checked -lt 10 ]]; then
  echo "FAIL only $checked executables in $bin_dir (build first)"
  exit 1
fi
echo "$checked executables, $failures failures"
[[ $failures -eq 0 ]]
