#!/usr/bin/env python3
"""scripts/operator_search.py: variants stay inside the search space and keep the base's other keys;
`run` drives a bench (here a stand-in with a hidden effect: a trial succeeds when a draw, independent
per variant and seed, as the real bench's outcomes nearly are (docs/teleop.md), is below 0.25 + 0.4 x
grasp_below_top_m's move in units of its range, whatever the other keys are), keeps
one result file per job and reports a failing job; `report` pairs every variant with v000 on the same
seeds and finds the hidden effect (and only it) by least squares over all trials."""
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "operator_search.py"
BASE = ROOT / "config" / "tasks" / "box_operator.yaml"

FAKE_BENCH = r'''
import argparse, json, random, sys, yaml
from pathlib import Path
p = argparse.ArgumentParser()
for k in ("--task", "--trials", "--seed", "--operator", "--out"):
    p.add_argument(k)
p.add_argument("--no-figures", action="store_true")
a = p.parse_args()
op = yaml.safe_load(open(a.operator))
if op.get("squeeze_s", 0) > 2.9:
    print("fake bench: refusing squeeze_s", file=sys.stderr)
    sys.exit(1)
lift = 0.25 + 0.4 * (op["grasp_below_top_m"] - 0.06) / 0.09
out = Path(a.out); out.mkdir(parents=True)
trials = []
for k in range(int(a.trials)):
    u = random.Random(f"{int(a.seed) + k}-{Path(a.operator).stem}").random()  # independent per variant and seed
    trials.append({"trial": k, "success": u < lift, "measure": {}, "fell": False, "regrabs": 0, "seconds": 1.0})
fails = [{"trial": t["trial"], "reason": "dropped"} for t in trials if not t["success"]]
json.dump({"task": a.task, "trials": len(trials), "successes": sum(t["success"] for t in trials),
           "trial_results": trials, "failures": fails}, open(out / "summary.json", "w"))
'''


def run(*args):
    r = subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def main():
    base = yaml.safe_load(BASE.read_text())
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        run("sample", "--base", BASE, "--n", 59, "--seed", 3, "--p-move", 0.3, "--out", d)
        meta = json.loads((d / "variants.json").read_text())
        space = meta["space"]
        files = sorted((d / "variants").glob("v*.yaml"))
        assert len(files) == 60, files
        assert yaml.safe_load(files[0].read_text()) == base, "v000 is the base"
        assert meta["variants"]["v000"]["moved"] == {}
        for f in files[1:]:
            v = yaml.safe_load(f.read_text())
            moved = meta["variants"][f.stem]["moved"]
            assert moved, f"{f.stem}: nothing moved"
            for key, val in v.items():
                if key in moved:
                    rng = space[key]
                    if isinstance(val, bool) or not isinstance(rng[0], float) or len(rng) != 2:
                        assert val in rng, (f.stem, key, val, rng)
                    else:
                        assert rng[0] <= val <= rng[1], (f.stem, key, val, rng)
                else:
                    assert val == base[key], (f.stem, key, val)
        assert any("grasp_below_top_m" in meta["variants"][f.stem]["moved"] for f in files), "the planted key is moved somewhere"

        # `make`: overrides on the base; a key the bench does not know is refused.
        run("make", "--base", BASE, "--set", "hand_pitch_rad=-0.3", "unwind_on_release=true", "--out", d / "made.yaml")
        made = yaml.safe_load((d / "made.yaml").read_text())
        assert made["hand_pitch_rad"] == -0.3 and made["unwind_on_release"] is True and made["crouch_m"] == base["crouch_m"]
        r = subprocess.run([sys.executable, str(SCRIPT), "make", "--base", str(BASE), "--set", "no_such_key=1", "--out", str(d / "x.yaml")],
                           capture_output=True, text=True, cwd=ROOT)
        assert r.returncode != 0 and "no_such_key" in (r.stdout + r.stderr)

        # `run` with the stand-in bench: every (variant, seed block) job kept; a refused variant is reported.
        (d / "fake_bench.py").write_text(FAKE_BENCH)
        run("make", "--base", BASE, "--set", "squeeze_s=2.95", "--out", d / "refused.yaml")  # the stand-in refuses it
        bad = [f for f in files if yaml.safe_load(f.read_text()).get("squeeze_s", 0) > 2.9] + [d / "refused.yaml"]
        out = run("run", "--variants", *files, d / "refused.yaml", "--seeds", "100:500", "--per-job", 200, "--procs", 2,
                  "--bench", f"{sys.executable} {d / 'fake_bench.py'}", "--out", d)
        results = sorted((d / "results").glob("*.json"))
        assert len(results) == 2 * (61 - len(bad)), (len(results), len(bad))
        assert out.count("FAILED") == 2 * len(bad), out
        assert f"({2 * len(bad)} failed)" in out, out

        out = run("report", "--out", d)
        rep = json.loads((d / "report.json").read_text())
        assert rep["variants"]["v000"]["trials"] == 400
        for name, v in rep["variants"].items():
            assert v["common_with_v000"] == 400
        eff = rep["effects"]
        b, se = eff["grasp_below_top_m"]["effect_per_range"], eff["grasp_below_top_m"]["se"]
        assert abs(b - 0.4) < 3 * se + 0.05 and b / se > 4, (b, se)
        print(f"hidden effect 0.4 per range: found {b:+.3f} +- {se:.3f}")
        for key, e in eff.items():
            if key != "grasp_below_top_m" and e["se"] > 0:
                assert abs(e["effect_per_range"] / e["se"]) < 4.0, (key, e)
        # Fewer variants than parameters moved: the effects are not identifiable, and the report says so.
        few = d / "few"
        (few / "results").mkdir(parents=True)
        (few / "variants.json").write_text((d / "variants.json").read_text())
        for f in results:
            if f.name.split("_")[0] in {f"v{i:03d}" for i in range(8)}:
                (few / "results" / f.name).write_text(f.read_text())
        out = run("report", "--out", few)
        assert "parameter effects not estimated" in out, out
        assert "effects" not in json.loads((few / "report.json").read_text()) or not json.loads((few / "report.json").read_text())["effects"]
    print("operator_search: variants, run and report as built")


if __name__ == "__main__":
    main()
