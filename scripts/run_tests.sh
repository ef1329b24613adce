#!/usr/bin/env bash
# Runs the whole test suite (unit + SIL) on an existing build/. Extra arguments go to ctest
# (e.g. -L unit for the quick ones only).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
# MuJoCo's compiled G1 model is kept between the suite's processes (loadMujocoModel's opt-in cache,
# include/pmg/common/mujoco_model.hpp): 230 of the SIL label's 333 compiles were the same few models.
export PMG_MJCF_CACHE_DIR="${PMG_MJCF_CACHE_DIR:-$root/build/mjcf_cache}"
ctest --test-dir build --output-on-failure -j "${PMG_TEST_JOBS:-2}" --timeout 600 "$@"
