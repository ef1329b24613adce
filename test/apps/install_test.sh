#!/usr/bin/env bash
# The install tree: `cmake --install BUILD_DIR --prefix P` into a temporary prefix, then
#  1. a consumer project (CONSUMER_SRC, test/apps/install_consumer) configured with only
#     CMAKE_PREFIX_PATH=P finds pmg with find_package(pmg), builds against pmg::generator and
#     pmg::common and runs;
#  2. installed tools run from a folder outside the checkout and find their data in P/share/pmg,
#     also after the prefix was moved (nothing points back into the build or source tree).
#   install_test.sh BUILD_DIR CONSUMER_SRC
set -euo pipefail
build="$(cd "${1:?usage: install_test.sh BUILD_DIR CONSUMER_SRC}" && pwd)"
consumer="$(cd "${2:?usage: install_test.sh BUILD_DIR CONSUMER_SRC}" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
unset PMG_DATA_DIR

echo "== cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
for f in lib/cmake/pmg/pmgConfig.cmake lib/cmake/pmg/pmgConfigVersion.cmake lib/cmake/pmg/pmgTargets.cmake \
         bin/pmg_controller bin/pmg_log_export bin/pmg_plot_tracking.py include/pmg/generator/generator.hpp \
         include/pmg/common/data_paths.hpp include/pmg_lcm/controller_state_t.hpp \
         share/pmg/config/robots/g1/g1.yaml share/pmg/config/policies/g1_pmg_policy.onnx \
         share/pmg/data/motions share/pmg/scripts/calib_plot.py share/pmg/scripts/pmg_plot_zero.py; do
  [[ -e "$prefix/$f" ]] || { echo "FAIL not installed: $f"; exit 1; }
done
if [[ -L "$prefix/share/pmg/config" ]]; then
  echo "FAIL share/pmg/config is a link (the install tree must hold copies)"
  exit 1
fi
source_dir="$(cd "$consumer/../../.." && pwd)"
if grep -rnF -e "$build" -e "$source_dir" "$prefix/lib/cmake/pmg"; then
  echo "FAIL the installed CMake package refers to the build or source tree (above)"
  exit 1
fi
for exe in "$prefix"/bin/*; do
  if [[ "$(head -c 4 "$exe")" == $'\x7fELF' ]] && readelf -d "$exe" | grep -E "R(UN)?PATH" | grep -qF -e "$build" -e "$source_dir"; then
    echo "FAIL $exe: RUNPATH into the build or source tree: $(readelf -d "$exe" | grep -E 'R(UN)?PATH')"
    exit 1
  fi
done

echo "== consumer: find_package(pmg) against the install tree"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$consumer" -B "$work/consumer" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >"$work/consumer-configure.log" || { cat "$work/consumer-configure.log"; exit 1; }
cmake --build "$work/consumer" -j "${PMG_BUILD_JOBS:-2}" >"$work/consumer-build.log" || { cat "$work/consumer-build.log"; exit 1; }
PMG_DATA_DIR="$prefix/share/pmg" "$work/consumer/pmg_consumer"

echo "== installed tools from outside the tree (data from share/pmg), then from a moved prefix"
mkdir "$work/elsewhere"
cd "$work/elsewhere"
for p in "$prefix" "$work/moved"; do
  if [[ "$p" == "$work/moved" ]]; then
    mv "$prefix" "$p"
  fi
  "$p/bin/pmg_policy_check" --model "$p/share/pmg/config/policies/g1_pmg_policy.onnx"
  plan="$("$p/bin/pmg_bus_plan" "$p/share/pmg/config/hal/g1_can.yaml")"
  echo "${plan%%$'\n'*}"
  help="$("$p/bin/pmg_policy_check" --help)"
  [[ "$help" == *"$p/share/pmg/config/robots/g1/g1.yaml"* ]] ||
    { echo "FAIL pmg_policy_check's default robot config is not in $p/share/pmg"; exit 1; }
done
if [[ -n "$(ls -A "$work/elsewhere")" ]]; then
  echo "FAIL the tools wrote into the working directory: $(ls -A "$work/elsewhere")"
  exit 1
fi
echo "install tree OK"
