#!/usr/bin/env bash
# Runs the whole test suite (unit + SIL) on an existing build/. Extra arguments go to ctest
# (e.g. -L unit for the quick ones only).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
ctest --test-dir build --output-on-failure -j "${PMG_TEST_JOBS:-2}" --timeout 600 "$@"
