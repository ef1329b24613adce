#!/usr/bin/env python3
"""actor_from_onnx.py inverts export_onnx.py (ctest training_actor_from_onnx; numpy, pyyaml, onnx, no JAX).

An actor.npz saved with its run (V20e's) is exported to ONNX, read back, and every array eval_mjx.py and
export_onnx.py use must come back: the normaliser and weights bit for bit, the action scale, clips, mode,
reference settings and clips digest equal. The actor the NumPy forward pass computes from both is the same
on random observations. A file without a pmg.contract is refused with its name in the message."""
import os
import subprocess
import sys
import tempfile

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, ".."))
import actor_from_onnx  # noqa: E402
import export_onnx  # noqa: E402
from pmg_train.contract import actor_forward  # noqa: E402

src = os.path.join(here, "..", "results", "fidelity", "seeds_V20b", "V20e", "actor.npz")
failures = []
with tempfile.TemporaryDirectory() as tmp:
    onnx_path = os.path.join(tmp, "a.onnx")
    export_onnx.export(src, onnx_path)
    back = actor_from_onnx.actor_arrays(onnx_path)
    z = np.load(src)
    for k in z.files:
        a, b = z[k], back.get(k)
        if b is None:
            failures.append(f"{k}: not read back")
        elif a.dtype.kind in "fc" and not np.array_equal(a.astype(np.float32), b.astype(np.float32)):
            failures.append(f"{k}: differs (max |diff| {np.max(np.abs(a - b)):.2e})")
        elif a.dtype.kind not in "fc" and not np.array_equal(a, b):
            failures.append(f"{k}: {a} read back as {b}")
    mean, std, layers, _, _, _ = export_onnx.load_actor(src)
    out = os.path.join(tmp, "actor.npz")
    np.savez(out, **back)
    mean2, std2, layers2, _, _, _ = export_onnx.load_actor(out)
    obs = np.random.default_rng(1).standard_normal((16, mean.size)).astype(np.float32)
    d = np.max(np.abs(actor_forward(mean, std, layers, 12, obs) - actor_forward(mean2, std2, layers2, 12, obs)))
    if d != 0.0:
        failures.append(f"actions differ by {d:.2e}")
    bad = os.path.join(tmp, "bad.onnx")
    import onnx
    m = onnx.load(onnx_path)
    del m.metadata_props[:]
    onnx.save(m, bad)
    r = subprocess.run([sys.executable, os.path.join(here, "..", "actor_from_onnx.py"), bad, "--out", out],
                       capture_output=True, text=True)
    if r.returncode == 0 or "bad.onnx" not in r.stderr or "pmg.contract" not in r.stderr:
        failures.append(f"no contract: exit {r.returncode}, stderr {r.stderr.strip()!r}")
for f in failures:
    print("FAIL:", f)
print("actor_from_onnx round trip:", "ok" if not failures else f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
