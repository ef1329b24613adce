#!/usr/bin/env bash
# Builds .whl/site.tgz: the Python packages train_pmg.py needs on the GPU machine beyond its
# preinstalled JAX 0.11.2 / flax / optax / orbax / onnx (that machine has no package registry).
# Wheels for CPython 3.12 manylinux are unpacked without dependencies, unused parts (MuJoCo
# studio/viewer/renderer, MJX test data, PyOpenGL) are dropped to stay under the device tool's
# 64 MiB transfer limit, and the rest is tarred. The device command unpacks it and sets PYTHONPATH:
#   mkdir -p /tmp/site && tar xzf .whl/site.tgz -C /tmp/site && export PYTHONPATH=/tmp/site
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tmp="$(mktemp -d)"
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
  --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
  --platform manylinux2014_x86_64 --platform manylinux1_x86_64 --platform any -d "$tmp" \
  mujoco==3.17.0 mujoco-mjx==3.17.0 brax==0.14.2 glfw==2.11.0 websockets==17.4 trimesh==5.2.0 jaxopt==0.8.5 \
  tensorboardx==2.6.5 flask==3.1.3 flask-cors==6.0.5 ml-collections==1.1.0 blinker==1.9.0 itsdangerous==2.2.0
mkdir -p "$tmp/site"
for w in "$tmp"/*.whl; do unzip -q -o "$w" -d "$tmp/site"; done
# Dropped as well: packages that pip requires but that train_pmg.py never imports (checked with
# sys.modules after importing train_pmg, the env and Brax PPO: flask, websockets, tensorboardX, glfw
# with MUJOCO_GL=disable) and MuJoCo's C headers: the tracked tree has grown, and tree + site must
# stay under the 64 MiB a device command carries.
rm -rf "$tmp/site/mujoco/experimental" "$tmp/site/mujoco/mjx/test_data" "$tmp/site"/mujoco/_render_filament* \
       "$tmp/site"/mujoco/_simulate* "$tmp/site/OpenGL" "$tmp/site/mujoco/include" "$tmp/site"/flask* \
       "$tmp/site"/websockets* "$tmp/site"/tensorboardX* "$tmp/site"/glfw "$tmp/site"/glfw-* \
       "$tmp/site"/blinker* "$tmp/site"/itsdangerous*
mkdir -p "$root/.whl"
tar czf "$root/.whl/site.tgz" -C "$tmp/site" .
rm -rf "$tmp"
echo "wrote $root/.whl/site.tgz ($(du -h "$root/.whl/site.tgz" | cut -f1))"
