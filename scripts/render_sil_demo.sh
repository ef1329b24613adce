#!/usr/bin/env bash
# The rendered frames of the SIL demo, and the picture in docs/render.md:
#   1. out/sil_demo/run.lcmlog from scripts/run_sil_demo.sh (run first if the log is missing);
#   2. out/sil_demo/render/gait_cycle.png: 8 frames over one gait cycle of the forward walk
#      (vx = 0.5 m/s from t = 2 s), the robot hanging in the gantry, its legs walking;
#   3. out/sil_demo/render/overview.png: one frame per command segment (stand, forward, turn,
#      combined, backward, stop);
#   4. with --docs: copies gait_cycle.png to docs/img/render_sil_demo.png.
# Xvfb is started when $DISPLAY is unset (scripts/render_sil.sh). PMG_BUILD_DIR picks the build folder.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out=out/sil_demo
if [ ! -f "$out/run.lcmlog" ]; then scripts/run_sil_demo.sh "$out"; fi
# The SIL gantry holds the pelvis at (0, 0, 0.95) m (config/controller/g1_sil.yaml): rope from above it.
common=(--tether 0 0 2.5 --width 300 --height 480)
scripts/render_sil.sh "$out/run.lcmlog" "$out/render" --strip gait_cycle.png --frames 8 --t0 3.0 --one-cycle \
  "${common[@]}"
scripts/render_sil.sh "$out/run.lcmlog" "$out/render" --strip overview.png --frames 7 --t0 1.0 --t1 13.0 \
  "${common[@]}"
if [ "${1:-}" = "--docs" ]; then
  mkdir -p docs/img
  cp "$out/render/gait_cycle.png" docs/img/render_sil_demo.png
  echo "docs/img/render_sil_demo.png updated"
fi
