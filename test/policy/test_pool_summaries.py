#!/usr/bin/env python3
"""scripts/pool_summaries.py: seed-weighted means of two synthetic summaries, falls summed, and a
mismatched script refused with exit status 2 naming the file."""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "pool_summaries.py")


def summary(seeds, pitch, vx, fallen, name="crouch_walk"):
    cmd = {"vx": 0.4, "vy": 0, "wz": 0, "pitch": 0, "roll": 0, "height": 0.68}
    seg = {"name": name, "seeds": seeds, "fallen": fallen, "command": cmd,
           "reference": dict(cmd), "achieved": dict(cmd, pitch=pitch, vx=vx)}
    return {"segments": [seg], "runs": [{"seed": 0}], "mean": {}}


def run(tmp, *summaries):
    paths = []
    for i, s in enumerate(summaries):
        p = os.path.join(tmp, f"s{i}.json")
        with open(p, "w") as f:
            json.dump(s, f)
        paths.append(p)
    out = os.path.join(tmp, "pooled.json")
    r = subprocess.run([sys.executable, SCRIPT, out] + paths, capture_output=True, text=True)
    return r, out, paths


def main():
    with tempfile.TemporaryDirectory() as tmp:
        r, out, paths = run(tmp, summary(6, -0.06, 0.40, 0), summary(2, -0.02, 0.32, 1))
        assert r.returncode == 0, r.stderr
        with open(out) as f:
            pooled = json.load(f)
        seg = pooled["segments"][0]
        assert seg["seeds"] == 8 and seg["fallen"] == 1, seg
        assert abs(seg["achieved"]["pitch"] - (6 * -0.06 + 2 * -0.02) / 8) < 1e-12, seg["achieved"]
        assert abs(seg["achieved"]["vx"] - (6 * 0.40 + 2 * 0.32) / 8) < 1e-12, seg["achieved"]
        assert "runs" not in pooled and pooled["pooled_from"] == paths
        # A different script (another segment name) is refused, naming the file.
        r, out, paths = run(tmp, summary(6, -0.06, 0.40, 0), summary(2, -0.02, 0.32, 0, name="crouch_turn"))
        assert r.returncode == 2 and paths[1] in r.stderr, (r.returncode, r.stderr)
    print("pool_summaries: OK")


if __name__ == "__main__":
    main()
