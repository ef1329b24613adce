#!/usr/bin/env python3
"""scripts/pelvis_pitch.py on a synthetic pmg_policy_sil output: two segments, the pelvis pitched
by a known angle (hip links placed by the G1's pelvis geometry, heading along +y), the torso pitch
given per tick. The script must recover the pelvis pitch and the waist's share per segment; and
scripts/plot_pelvis_pitch.py must draw its table and refuse a file that is not one."""
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
HIP_Y, HIP_Z = 0.064452, -0.1027  # hip pitch links in the pelvis frame [m]


def rotate(p, pitch, yaw):
    """Ry(pitch) then Rz(yaw) applied to p (pelvis frame -> world)."""
    x, y, z = p
    x, z = x * math.cos(pitch) + z * math.sin(pitch), -x * math.sin(pitch) + z * math.cos(pitch)
    return x * math.cos(yaw) - y * math.sin(yaw), x * math.sin(yaw) + y * math.cos(yaw), z


def main():
    segments = [("walk", -0.25, 0.0), ("bend", 0.02, 0.30)]  # (name, pelvis pitch, torso pitch)
    yaw = math.pi / 2
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "seed0.csv"), "w") as f, open(os.path.join(d, "frames0.csv"), "w") as g:
            f.write("t,segment,pitch\n")
            g.write("t,pelvis:0,left_hip_pitch_link:1,right_hip_pitch_link:1\n")
            t = 0.0
            for name, pelvis_pitch, torso_pitch in segments:
                for k in range(100):
                    # The first 40 % of each segment is a transient the script must ignore.
                    pp = pelvis_pitch if k >= 40 else 0.5
                    tp = torso_pitch if k >= 40 else -0.5
                    f.write(f"{t:.2f},{name},{tp}\n")
                    if k % 10 == 0:
                        base = (1.0, 2.0, 0.75)
                        cols = [base]
                        for side in (1, -1):
                            o = rotate((0.0, side * HIP_Y, HIP_Z), pp, yaw)
                            cols.append(tuple(b + c for b, c in zip(base, o)))
                        g.write(f"{t:.2f}," + ",".join(" ".join(f"{v:.9f}" for v in c) for c in cols) + "\n")
                    t += 0.01
        out = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "pelvis_pitch.py"), d],
                             capture_output=True, text=True, check=True).stdout
    print(out)
    rows = {line.split()[0]: [float(x) for x in line.split()[1:]] for line in out.splitlines()[2:]}
    ok = True
    for name, pelvis_pitch, torso_pitch in segments:
        torso, pelvis, waist = rows[name]
        good = abs(torso - torso_pitch) < 1e-6 and abs(pelvis - pelvis_pitch) < 1e-6 and \
            abs(waist - (torso_pitch - pelvis_pitch)) < 1e-6
        print(f"{'ok' if good else 'FAIL'} {name}: torso {torso:+.3f} pelvis {pelvis:+.3f} waist {waist:+.3f}")
        ok &= good
    # scripts/plot_pelvis_pitch.py draws that table, and refuses a file that is not one.
    plot = os.path.join(ROOT, "scripts", "plot_pelvis_pitch.py")
    with tempfile.TemporaryDirectory() as d:
        table, bad, png = os.path.join(d, "t.txt"), os.path.join(d, "bad.txt"), os.path.join(d, "p.png")
        with open(table, "w") as f:
            f.write(out)
        with open(bad, "w") as f:
            f.write("not a table\n")
        r = subprocess.run([sys.executable, plot, png, f"A={table}", "--segments", "walk,bend"], capture_output=True, text=True)
        drawn = r.returncode == 0 and os.path.getsize(png) > 1000
        r = subprocess.run([sys.executable, plot, png, f"A={bad}"], capture_output=True, text=True)
        refused = r.returncode != 0 and "bad.txt" in r.stderr
        print(f"{'ok' if drawn else 'FAIL'} plot drawn; {'ok' if refused else 'FAIL'} bad table refused ({r.stderr.strip()})")
        ok &= drawn and refused
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
