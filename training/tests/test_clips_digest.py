#!/usr/bin/env python3
"""pmg_train.contract.clips_digest, the contract's pmg.clips_digest on the training side: on
config/clips/g1_walking_height it equals the digest in wh6hs's shipped contract (which the C++
pmg::clipsDigest of the same files matches: test Contract.ClipsDigestMustMatchWhereTheContractHasOne);
rewriting a clip file in another number format, or leaving the consistency map out, does not change
it; moving one joint value by 2e-4 rad does."""
import glob
import os
import shutil
import sys
import tempfile

import onnx
import yaml

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "training"))
from pmg_train.contract import clips_digest  # noqa: E402

failures = []
clip_dir = os.path.join(ROOT, "config", "clips", "g1_walking_height")
files = sorted(glob.glob(os.path.join(clip_dir, "*.yaml")))
digest = clips_digest(files)
model = onnx.load(os.path.join(ROOT, "config", "policies", "g1_pmg_policy_wh6hs.onnx"))
contract = yaml.safe_load({p.key: p.value for p in model.metadata_props}["pmg.contract"])
if contract["pmg"].get("clips_digest") != digest:
    failures.append(f"digest {digest}, wh6hs's contract {contract['pmg'].get('clips_digest')}")
if clips_digest(sorted(glob.glob(os.path.join(ROOT, "config", "clips", "g1", "*.yaml")))) == digest:
    failures.append("the captured and the raised clips give the same digest")
if clips_digest([f for f in files if not f.endswith("consistency_map.yaml")]) != digest:
    failures.append("the consistency map entered the digest")
with tempfile.TemporaryDirectory() as tmp:
    for f in files:
        shutil.copy(f, tmp)
    path = os.path.join(tmp, "walk_forward.yaml")
    with open(path) as f:
        doc = yaml.safe_load(f)
    with open(path, "w") as f:
        yaml.safe_dump(doc, f, default_flow_style=False)  # another layout and number format
    copies = sorted(glob.glob(os.path.join(tmp, "*.yaml")))
    if clips_digest(copies) != digest:
        failures.append("reformatting a clip file changed the digest")
    doc["q"][10][3] += 2e-4
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)
    if clips_digest(copies) == digest:
        failures.append("a joint value moved by 2e-4 rad left the digest as it was")
print("\n".join("FAIL: " + f for f in failures) if failures else f"clips_digest: {digest} as in wh6hs's contract; 4 checks")
sys.exit(1 if failures else 0)
