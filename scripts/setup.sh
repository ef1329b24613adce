#!/usr/bin/env bash
# One idempotent set-up for a fresh Debian bookworm machine (or this project's CI):
#   1. system packages (apt-get): compilers, CMake, Eigen, urdfdom, KDL, MuJoCo 2.2, NLopt, Ceres,
#      LCM, yaml-cpp, GoogleTest, Google Benchmark, CLI11, spdlog/fmt, pagmo (CMA-ES); GLFW, libpng,
#      Xvfb and Mesa's software OpenGL for pmg_render_log (docs/render.md); SDL2, libsodium,
#      Boost.Beast, OpenSSL, nlohmann-json and headless Chromium for teleoperation (docs/teleop.md);
#      gperftools' tcmalloc, which the training tests preload (one XLA compile of the smoke env's step ran
#      1.5-2x faster with it, the env part 13 % faster: docs/ci_timing.md);
#   2. Python packages for the plotting/report scripts (pip);
#   3. the training environment .venv-training (ignored by git): a venv with training/ installed
#      editable with its CPU extra, pinned by training/requirements-lock.txt (training/README.md);
#      ctest training_smoke_* runs in it. PMG_SKIP_TRAINING_TESTS=1 skips it (and those tests);
#   4. ONNX Runtime 1.24.4: libonnxruntime.so from the PyPI wheel + onnxruntime_c_api.h from the Go
#      module github.com/yalue/onnxruntime_go@v1.27.0, unpacked into third_party/onnxruntime/ (ignored
#      by git). A robot host with an official ONNX Runtime release passes -DONNXRUNTIME_ROOT= instead.
# Re-running it is cheap: every step checks whether its result is already there.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

sudo_cmd=""
if [ "$(id -u)" != "0" ]; then sudo_cmd="sudo"; fi

apt_packages=(
  build-essential cmake ninja-build pkg-config git unzip curl golang-go
  libeigen3-dev liburdfdom-dev liborocos-kdl-dev libkdl-parser-dev libmujoco-dev libqhull-dev
  libnlopt-dev libnlopt-cxx-dev libceres-dev liblcm-dev liblcm-bin libglib2.0-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev libspdlog-dev libfmt-dev libpagmo-dev
  python3 python3-pip python3-venv libtcmalloc-minimal4
  libglfw3-dev libpng-dev xvfb libgl1-mesa-dri
  libsdl2-dev libsodium-dev libboost-dev libssl-dev nlohmann-json3-dev chromium
)
missing=()
for p in "${apt_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] apt-get install ${missing[*]}"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}"
fi

py=python3
if ! $py -c "import numpy, matplotlib, yaml, onnx" 2>/dev/null; then
  echo "[setup] pip install numpy matplotlib pyyaml onnx"
  $py -m pip install -q numpy matplotlib pyyaml onnx || $py -m pip install -q --break-system-packages numpy matplotlib pyyaml onnx
fi

venv="$root/.venv-training"
if [ "${PMG_SKIP_TRAINING_TESTS:-0}" != "1" ]; then
  # Re-installed when the pins change (pyproject.toml, requirements-lock.txt), or when it does not import.
  want="$(cat "$root/training/pyproject.toml" "$root/training/requirements-lock.txt" | sha256sum | cut -d' ' -f1)"
  if [ "$(cat "$venv/.pmg-setup-stamp" 2>/dev/null)" != "$want" ] \
     || ! "$venv/bin/python" -c "import os, sys, jax, brax, mujoco.mjx, onnx, pmg_train.paths as p
sys.exit(not os.path.samefile(p.__file__, '$root/training/pmg_train/paths.py'))" >/dev/null 2>&1; then
    echo "[setup] training environment $venv: pip install -e 'training[cpu]' (training/requirements-lock.txt)"
    "$venv/bin/python" -c "" 2>/dev/null || $py -m venv --clear "$venv"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check \
      -c "$root/training/requirements-lock.txt" -e "$root/training[cpu]"
    echo "$want" > "$venv/.pmg-setup-stamp"
  fi
fi

ort_dir="$root/third_party/onnxruntime"
ort_ver=1.24.4
if [ ! -f "$ort_dir/lib/libonnxruntime.so.$ort_ver" ] || [ ! -f "$ort_dir/include/onnxruntime_c_api.h" ] \
   || [ ! -f "$ort_dir/include/onnxruntime_ep_c_api.h" ]; then
  echo "[setup] fetching ONNX Runtime $ort_ver (PyPI wheel + C API header)"
  tmp="$(mktemp -d)"
  $py -m pip download -q --no-deps --only-binary=:all: --dest "$tmp" \
      --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
      --python-version 3.11 "onnxruntime==$ort_ver"
  mkdir -p "$ort_dir/lib" "$ort_dir/include"
  (cd "$tmp" && unzip -q -o onnxruntime-*.whl 'onnxruntime/capi/libonnxruntime.so*')
  cp "$tmp"/onnxruntime/capi/libonnxruntime.so.* "$ort_dir/lib/"
  ln -sf "libonnxruntime.so.$ort_ver" "$ort_dir/lib/libonnxruntime.so.1"
  ln -sf "libonnxruntime.so.1" "$ort_dir/lib/libonnxruntime.so"
  export GOPATH="$tmp/go" GOFLAGS=-modcacherw
  (cd "$tmp" && go mod download -json github.com/yalue/onnxruntime_go@v1.27.0 >/dev/null)
  # onnxruntime_c_api.h includes onnxruntime_ep_c_api.h (since ORT 1.23): copy both.
  cp "$tmp/go/pkg/mod/github.com/yalue/onnxruntime_go@v1.27.0/onnxruntime_c_api.h" \
     "$tmp/go/pkg/mod/github.com/yalue/onnxruntime_go@v1.27.0/onnxruntime_ep_c_api.h" "$ort_dir/include/"
  rm -rf "$tmp"
fi
echo "[setup] done"
