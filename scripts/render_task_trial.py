#!/usr/bin/env python3
"""Frame strip of one pmg_teleop_bench trial (issue 14): runs pmg_render_log on the trial's event log
over the trial's task scene, with the object placed from its recorded track. MuJoCo's renderer needs
an OpenGL context on an X display: without $DISPLAY this starts a private Xvfb (as
scripts/render_sil.sh does) and stops it at exit. pmg_teleop_bench calls it for the first success
and the first failure; by hand:

    python3 scripts/render_task_trial.py --exe build/bin/pmg_render_log --log DIR/trial_3.lcmlog \\
        --mjcf DIR/trial_3_scene.xml --objects DIR/trial_3_objects.csv --out DIR/trial_3_strip.png \\
        [--frames 8] [--t0 1] [--t1 T]

Exit status: pmg_render_log's (0 done, 1 bad input, 3 no OpenGL), or 1 when no display can be had.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile


def start_xvfb():
    """Starts Xvfb on a free display number (-displayfd); returns (process, display, tmpdir)."""
    if shutil.which("Xvfb") is None:
        sys.exit("render_task_trial.py: $DISPLAY is not set and Xvfb is not installed (Debian: apt-get install xvfb)")
    tmp = tempfile.mkdtemp()
    r, w = os.pipe()
    with open(os.path.join(tmp, "xvfb.log"), "w") as log:
        proc = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                                pass_fds=(w,), stdout=log, stderr=log)
    os.close(w)
    with os.fdopen(r) as f:
        line = f.readline().strip()  # Xvfb writes the display number when it is ready
    if not line:
        proc.kill()
        sys.exit("render_task_trial.py: Xvfb reported no display number: " + open(os.path.join(tmp, "xvfb.log")).read())
    return proc, ":" + line, tmp


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exe", required=True, help="pmg_render_log executable")
    ap.add_argument("--log", required=True, help="the trial's event log (PMG_STATE telemetry)")
    ap.add_argument("--mjcf", required=True, help="the trial's task scene (robot + tables + objects)")
    ap.add_argument("--objects", required=True, help="the trial's object track CSV")
    ap.add_argument("--out", required=True, help="strip PNG to write")
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--t0", type=float, default=None)
    ap.add_argument("--t1", type=float, default=None)
    a = ap.parse_args()
    out = os.path.abspath(a.out)
    cmd = [a.exe, "--log", a.log, "--mjcf", a.mjcf, "--objects", a.objects, "--out-dir", os.path.dirname(out),
           "--strip", os.path.basename(out), "--frames", str(a.frames), "--width", "320", "--height", "420",
           "--azimuth", "145", "--elevation", "-20", "--distance", "2.6", "--lookat-dz", "-0.15",
           "--no-reflections", "--samples", "2"]
    if a.t0 is not None:
        cmd += ["--t0", str(a.t0)]
    if a.t1 is not None:
        cmd += ["--t1", str(a.t1)]
    env = dict(os.environ)
    xvfb, tmp = None, None
    if not env.get("DISPLAY"):
        xvfb, env["DISPLAY"], tmp = start_xvfb()
    try:
        return subprocess.call(cmd, env=env)
    finally:
        if xvfb is not None:
            xvfb.terminate()
            xvfb.wait()
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
