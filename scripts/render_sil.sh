#!/usr/bin/env bash
# Renders a pmg_controller event log (e.g. out/sil_demo/run.lcmlog from scripts/run_sil_demo.sh)
# to PNG files with build/bin/pmg_render_log: OUT_DIR/strip.png (a frame strip) and, with
# --video-fps F, OUT_DIR/frames/frame_NNNNN.png. Further arguments go to pmg_render_log
# (--frames, --t0, --t1, --azimuth, ...; see docs/render.md).
#   scripts/render_sil.sh out/sil_demo/run.lcmlog out/sil_demo/render --frames 8 --t0 2 --t1 14
# MuJoCo's renderer needs an OpenGL context on an X display: when $DISPLAY is unset, this script
# starts a private Xvfb (Mesa llvmpipe renders in software) on a free display number and stops it
# again at exit.
# Environment: PMG_BUILD_DIR (default build) picks the build folder; PMG_RENDER_LOG, the executable
# itself (pmg_teleop_bench sets it to the pmg_render_log beside it: this script is also installed
# into share/pmg/scripts).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ $# -lt 2 ]; then
  echo "usage: $0 LOG OUT_DIR [pmg_render_log options]" >&2
  exit 2
fi
log="$(realpath "$1")"              # absolute: the renderer runs in the repository root
mkdir -p "$2"
out="$(realpath "$2")"
shift 2
exe="${PMG_RENDER_LOG:-${PMG_BUILD_DIR:-$root/build}/bin/pmg_render_log}"
if [ ! -x "$exe" ]; then
  echo "render_sil.sh: $exe not found: build it first (ninja -C build pmg_render_log)" >&2
  exit 1
fi

xvfb_pid=""
tmp=""
cleanup() {
  if [ -n "$xvfb_pid" ]; then kill "$xvfb_pid" 2>/dev/null || true; wait "$xvfb_pid" 2>/dev/null || true; fi
  if [ -n "$tmp" ]; then rm -rf "$tmp"; fi
}
trap cleanup EXIT
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v Xvfb >/dev/null; then
    echo "render_sil.sh: \$DISPLAY is not set and Xvfb is not installed (Debian: apt-get install xvfb;" \
         "scripts/setup.sh installs it)" >&2
    exit 1
  fi
  # -displayfd: Xvfb picks a free display number and writes it (one line) to fd 3 when ready.
  tmp="$(mktemp -d)"
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$tmp/display" >"$tmp/xvfb.log" 2>&1 &
  xvfb_pid=$!
  for _ in $(seq 100); do
    [ "$(wc -l <"$tmp/display")" -ge 1 ] && break
    if ! kill -0 "$xvfb_pid" 2>/dev/null; then
      echo "render_sil.sh: Xvfb exited at start-up; its log:" >&2
      cat "$tmp/xvfb.log" >&2
      exit 1
    fi
    sleep 0.1
  done
  n="$(head -n 1 "$tmp/display")"
  if [ -z "$n" ]; then
    echo "render_sil.sh: Xvfb reported no display number within 10 s" >&2
    exit 1
  fi
  export DISPLAY=":$n"
  echo "render_sil.sh: started Xvfb on $DISPLAY (pid $xvfb_pid)"
fi
cd "$root"
"$exe" --log "$log" --out-dir "$out" "$@"
