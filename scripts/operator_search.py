#!/usr/bin/env python3
r"""Search a scripted teleop operator's parameters with many trials on many cores.

pmg_teleop_bench is deterministic per seed, so variants of an operator can be compared trial by trial
on the same seeds. Twenty trials per variant (the earlier tuning) cannot tell 0.25 from 0.35; this
tool runs hundreds per variant on a many-core machine (the device machines have 16-128 cores) and
estimates every parameter's effect from all trials at once.

  sample   draw variants of a base operator config: each parameter of the search space is moved,
           with probability --p-move, to a value drawn uniformly from its range (variant v000 is the
           base itself). Writes DIR/variants/vNNN.yaml and DIR/variants.json.
  make     write an operator YAML from a base and key=value overrides (a chosen candidate).
  run      run every (variant, seed block) job with --procs parallel processes, keeping only each
           job's per-trial results (DIR/results/<variant>_<seed>.json); jobs are ordered seed block
           by seed block, so a run stopped by --deadline-s leaves every variant on the same seeds.
  report   successes per variant, paired against v000 on the seeds both ran, and each parameter's
           effect on the success rate by least squares on all trials (a linear probability model
           with one intercept per seed, so the seeds' difficulty cancels), once there are more
           variants than parameters moved (else it says so). Writes DIR/report.json.

The bench command is --bench (default build/bin/pmg_teleop_bench); on a machine without the build's
libraries use a bundle from scripts/bundle_bench.sh: --bench "bundle/run.sh". On the device machines
(docs/teleop.md, "Operator search on many cores"), with the bundle and the variants carried in .bundle/:
  here:   scripts/bundle_bench.sh && python3 scripts/operator_search.py sample --n 47 --out .bundle/s1
  there:  tar xJf .bundle/bench.txz -C /tmp && python3 scripts/operator_search.py run \
            --variants .bundle/s1/variants/*.yaml --seeds 2000:2100 --bench /tmp/bundle/run.sh \
            --deadline-s 470 --out /tmp/s1; tar czf $OUT/s1.tgz -C /tmp s1/results
          (one archive: the device returns only a limited number of files)
  here:   tar xzf s1.tgz && cp .bundle/s1/variants.json s1/ && python3 scripts/operator_search.py report --out s1
Pure standard library in `run` (the device machines need nothing installed); `sample`/`make` need PyYAML.
"""
import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

# The box operator's search space: key -> (low, high) for a float, or a list of choices.
# Ranges are inside the bench's validated ranges (apps/teleop/pmg_teleop_bench.cpp, validate()).
BOX_SPACE = {
    "grasp_below_top_m": (0.03, 0.12),
    "grasp_in_m": (-0.06, 0.10),  # < 0: short of the near side (v6 -0.04, docs/teleop.md)
    "regrip_in_m": (0.10, 0.18),
    "slide_to_m": (-0.07, 0.0),
    "squeeze_m": (0.0, 0.06),
    "squeeze_s": (0.8, 3.0),
    "max_lead_m": (0.06, 0.14),
    "vertical_lead_m": [0.0, 0.05, 0.10],
    "lift_speed": (0.04, 0.15),
    "stand_s": (2.0, 6.0),
    "stand_after_lift_m": (0.02, 0.12),
    "carry_speed": (0.10, 0.25),
    "crouch_m": (0.14, 0.22),
    "look_down_rad": (0.60, 0.75),
    "stand_off_m": (0.17, 0.24),
    "carry_clearance_m": (0.05, 0.12),
    "hand_pitch_rad": (-0.2, 0.3),
    "hand_toe_in_rad": (-0.1, 0.2),
    "max_raise_m": (0.08, 0.20),
    "unwind_on_release": [False, True],
    "unwind_on_place": [False, True],
    "freeze_regrip_aim": [False, True],
    "release_clear_m": [0.0, 0.04, 0.06],
    "keep_hand_pitch": [False, True],
    "hug_m": [0.0, 0.05, 0.08],
    "place_in_m": (0.04, 0.12),
    "place_press_m": (0.0, 0.03),
}


# Values of the space's keys that a base config may leave out (the bench's defaults).
BOX_DEFAULTS = {"vertical_lead_m": 0.0, "unwind_on_release": False, "freeze_regrip_aim": False, "release_clear_m": 0.0,
                "keep_hand_pitch": False, "hug_m": 0.0, "place_in_m": 0.04, "hand_pitch_rad": 0.0, "hand_toe_in_rad": 0.0,
                "unwind_on_place": False, "place_flat_rad": 0.0}


def load_base(path):
    base = dict(BOX_DEFAULTS)
    base.update(load_yaml(path))
    return base


def load_yaml(path):
    import yaml
    with open(path) as f:
        return yaml.safe_load(f)


def write_operator(path, params, header):
    lines = [f"# {h}" for h in header] + [f"{k}: {json.dumps(v)}" for k, v in params.items()]
    Path(path).write_text("\n".join(lines) + "\n")


def cmd_sample(a):
    base = load_base(a.base)
    rng = random.Random(a.seed)
    out = Path(a.out)
    (out / "variants").mkdir(parents=True, exist_ok=True)
    table = {}
    for i in range(a.n + 1):
        moved = {}
        if i > 0:
            while not moved:
                for key, space in BOX_SPACE.items():
                    if rng.random() >= a.p_move:
                        continue
                    if isinstance(space, list):
                        choices = [c for c in space if c != base.get(key)] or space
                        moved[key] = rng.choice(choices)
                    else:
                        moved[key] = round(rng.uniform(*space), 4)
        params = load_yaml(a.base)
        params.update(moved)
        name = f"v{i:03d}"
        write_operator(out / "variants" / f"{name}.yaml", params,
                       [f"{name}: {a.base} with {json.dumps(moved) if moved else 'nothing moved (the base)'}",
                        "written by scripts/operator_search.py sample"])
        table[name] = {"moved": moved}
    (out / "variants.json").write_text(json.dumps({"base": base, "space": {k: list(v) if isinstance(v, tuple) else v for k, v in BOX_SPACE.items()},
                                                   "seed": a.seed, "p_move": a.p_move, "variants": table}, indent=1))
    print(f"{a.n + 1} variants in {out / 'variants'}")


def cmd_make(a):
    params = load_yaml(a.base)
    moved = {}
    for kv in a.set:
        key, _, val = kv.partition("=")
        if key not in params and key not in BOX_DEFAULTS:
            sys.exit(f"make: {key}: not a key of {a.base} nor of the search space's defaults (the bench refuses unknown keys)")
        moved[key] = json.loads(val)
    params.update(moved)
    write_operator(a.out, params, [f"{a.base} with {json.dumps(moved)}", "written by scripts/operator_search.py make"])


def run_job(bench, task, variant_file, seed, trials, results_dir, scratch, scene=""):
    name = Path(variant_file).stem
    dest = results_dir / f"{name}_{seed}.json"
    if dest.exists():
        return dest, 0.0, "cached"
    work = Path(tempfile.mkdtemp(dir=scratch))
    t0 = time.time()
    try:
        cmd = bench.split() + ["--task", task, "--trials", str(trials), "--seed", str(seed), "--no-figures",
                               "--operator", str(variant_file), "--out", str(work / "o")] + (["--scene", scene] if scene else [])
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        summary = work / "o" / "summary.json"
        if p.returncode != 0 or not summary.exists():
            return dest, time.time() - t0, f"rc {p.returncode}: {p.stdout[-400:]}"
        s = json.loads(summary.read_text())
        keep = {"variant": name, "seed": seed, "trials": s["trials"], "successes": s["successes"],
                "trial_results": [{k: t.get(k) for k in ("trial", "success", "measure", "fell", "regrabs", "seconds")} |
                                  {"reason": next((f["reason"] for f in s["failures"] if f["trial"] == t["trial"]), None)}
                                  for t in s["trial_results"]]}
        tmp = dest.with_suffix(".tmp")
        tmp.write_text(json.dumps(keep))
        tmp.rename(dest)
        return dest, time.time() - t0, "ok"
    finally:
        shutil.rmtree(work, ignore_errors=True)


def cmd_run(a):
    out = Path(a.out)
    results = out / "results"
    results.mkdir(parents=True, exist_ok=True)
    variants = sorted(Path(v) for v in a.variants)
    first, last = (int(x) for x in a.seeds.split(":"))
    blocks = list(range(first, last, a.per_job))
    jobs = [(v, s, min(a.per_job, last - s)) for s in blocks for v in variants]
    scratch = Path(a.scratch or tempfile.gettempdir())
    t_start = time.time()
    done = failed = 0
    print(f"{len(jobs)} jobs ({len(variants)} variants x seeds {first}..{last - 1}, {a.per_job} per job) on {a.procs} processes", flush=True)

    def job(j):  # a job not started by the deadline is skipped (jobs go seed block by seed block)
        if a.deadline_s and time.time() - t_start > a.deadline_s:
            return None
        return run_job(a.bench, a.task, j[0], j[1], j[2], results, scratch, a.scene)

    with ThreadPoolExecutor(max_workers=a.procs) as pool:
        futures = {pool.submit(job, j): j for j in jobs}
        for fut in as_completed(futures):
            j, r = futures[fut], fut.result()
            if r is None:
                continue
            dest, secs, status = r
            done += 1
            if status not in ("ok", "cached"):
                failed += 1
                print(f"FAILED {j[0].stem} seed {j[1]}: {status}", flush=True)
            if done % max(1, len(jobs) // 40) == 0 or status not in ("ok", "cached"):
                print(f"[{time.time() - t_start:6.0f} s] {done}/{len(jobs)} jobs, last {secs:.0f} s", flush=True)
    print(f"done: {done} of {len(jobs)} jobs ({failed} failed) in {time.time() - t_start:.0f} s", flush=True)


def load_results(out):
    """(variant, seed, success, reason) of every trial under DIR: DIR/results/*.json as `run` writes
    them, or a study's compact DIR/trials.json ({"variants" or "scenes": {name: {"trials": [...]}}})."""
    rows = []
    for f in sorted((Path(out) / "results").glob("*.json")):
        r = json.loads(f.read_text())
        for t in r["trial_results"]:
            rows.append((r["variant"], r["seed"] + t["trial"], bool(t["success"]), t.get("reason")))
    compact = Path(out) / "trials.json"
    if compact.exists():
        c = json.loads(compact.read_text())
        for name, v in (c.get("variants") or c.get("scenes") or {}).items():
            rows += [(name, t["seed"], bool(t["success"]), t.get("reason")) for t in v["trials"]]
    return rows


def sign_test_p(gained, lost):
    """Two-sided exact sign test (McNemar's exact test) on the discordant pairs."""
    import math
    n, k = gained + lost, min(gained, lost)
    if n == 0:
        return 1.0
    return min(1.0, 2.0 * sum(math.comb(n, i) for i in range(k + 1)) / 2.0 ** n)


def cmd_report(a):
    import numpy as np
    out = Path(a.out)
    meta = json.loads((out / "variants.json").read_text()) if (out / "variants.json").exists() else {"variants": {}}
    rows = load_results(out)
    for extra in a.with_:
        rows += [r for r in load_results(extra) if r[0] == "v000"]  # the base, run in another study on the same seeds
    by_var = {}
    for v, s, ok, reason in rows:
        by_var.setdefault(v, {})[s] = (ok, reason)
    base = by_var.get("v000", {})
    report = {"variants": {}, "effects": {}}
    print(f"{'variant':8s} {'succ':>9s} {'rate':>5s}  paired vs v000: gained/lost of common, sign-test p   failures   moved")
    order = sorted(by_var, key=lambda v: -sum(ok for ok, _ in by_var[v].values()) / max(1, len(by_var[v])))
    for v in order:
        d = by_var[v]
        n, k = len(d), sum(ok for ok, _ in d.values())
        common = [s for s in d if s in base]
        gained = sum(d[s][0] and not base[s][0] for s in common)
        lost = sum(base[s][0] and not d[s][0] for s in common)
        reasons = {}
        for ok, r in d.values():
            if not ok:
                reasons[r] = reasons.get(r, 0) + 1
        moved = meta["variants"].get(v, {}).get("moved", {})
        p = sign_test_p(gained, lost)
        report["variants"][v] = {"trials": n, "successes": k, "rate": k / n, "gained_vs_v000": gained,
                                 "lost_vs_v000": lost, "common_with_v000": len(common), "sign_test_p": p,
                                 "failures": reasons, "moved": moved}
        print(f"{v:8s} {k:4d}/{n:<4d} {k / n:5.2f}  +{gained:<3d} -{lost:<3d} of {len(common):<4d} p {p:5.3f}  "
              f"{json.dumps(dict(sorted(reasons.items(), key=lambda r: -r[1])))}  {json.dumps(moved)}")
    # Effects: success ~ seed intercepts + sum_k beta_k x_k, x_k = the variant's parameter minus the base's,
    # in units of the parameter's range (bools and choices likewise), least squares on every trial.
    space, base_params = meta.get("space", {}), meta.get("base", {})
    if space and rows:
        keys = list(space)

        def feature(v, key):
            moved = meta["variants"].get(v, {}).get("moved", {})
            if key not in moved:
                return 0.0
            rng = space[key]
            val, b = moved[key], base_params.get(key)
            if isinstance(val, bool) or isinstance(b, bool):
                return float(val) - float(bool(b))
            lo, hi = (min(rng), max(rng))
            return (float(val) - float(b)) / (hi - lo)

        seeds = sorted({s for _, s, _, _ in rows})
        sidx = {s: i for i, s in enumerate(seeds)}
        X = np.zeros((len(rows), len(seeds) + len(keys)))
        y = np.zeros(len(rows))
        for i, (v, s, ok, _) in enumerate(rows):
            X[i, sidx[s]] = 1.0
            for j, key in enumerate(keys):
                X[i, len(seeds) + j] = feature(v, key)
            y[i] = ok
        # Identifiable only with more distinct variants than parameters: with fewer, least squares
        # returns the minimum-norm answer, which shrinks every effect towards zero.
        variant_features = np.array([[feature(v, key) for key in keys] for v in sorted(by_var)])
        rank = np.linalg.matrix_rank(variant_features - variant_features.mean(axis=0)) if len(by_var) > 1 else 0
        moved_keys = int(np.count_nonzero(np.abs(variant_features).sum(axis=0)))
        if rank < moved_keys:
            print(f"\nparameter effects not estimated: {len(by_var)} variants span only {rank} of the {moved_keys} parameters "
                  f"moved (sample more variants than parameters)")
            report["effects_not_identifiable"] = {"variants": len(by_var), "rank": int(rank), "parameters_moved": moved_keys}
            (out / "report.json").write_text(json.dumps(report, indent=1))
            return
        beta, *_ = np.linalg.lstsq(X, y, rcond=None)
        resid = y - X @ beta
        dof = max(1, len(rows) - np.linalg.matrix_rank(X))
        sigma2 = float(resid @ resid) / dof
        cov = sigma2 * np.linalg.pinv(X.T @ X)
        print("\nparameter effects (success-rate change per full range move, ± standard error; + = the range's high end helps):")
        eff = []
        for j, key in enumerate(keys):
            b, se = beta[len(seeds) + j], float(np.sqrt(max(cov[len(seeds) + j, len(seeds) + j], 0)))
            eff.append((key, float(b), se))
        for key, b, se in sorted(eff, key=lambda e: -abs(e[1]) / max(e[2], 1e-9)):
            print(f"  {key:22s} {b:+.3f} ± {se:.3f}  (t {b / se if se > 0 else 0:+.1f})  range {space[key]}, base {base_params.get(key)}")
            report["effects"][key] = {"effect_per_range": b, "se": se, "range": space[key], "base": base_params.get(key)}
    (out / "report.json").write_text(json.dumps(report, indent=1))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("sample")
    s.add_argument("--base", default="config/tasks/box_operator.yaml")
    s.add_argument("--n", type=int, required=True, help="variants besides the base")
    s.add_argument("--seed", type=int, default=1)
    s.add_argument("--p-move", type=float, default=0.3)
    s.add_argument("--out", required=True)
    m = sub.add_parser("make")
    m.add_argument("--base", default="config/tasks/box_operator.yaml")
    m.add_argument("--set", nargs="+", default=[], help="key=value (value as JSON)")
    m.add_argument("--out", required=True)
    r = sub.add_parser("run")
    r.add_argument("--variants", nargs="+", required=True, help="operator YAML files")
    r.add_argument("--seeds", required=True, help="FIRST:END (END exclusive)")
    r.add_argument("--per-job", type=int, default=4)
    r.add_argument("--procs", type=int, default=os.cpu_count())
    r.add_argument("--task", default="box", choices=["box", "wipe"])
    r.add_argument("--bench", default="build/bin/pmg_teleop_bench")
    r.add_argument("--scene", default="", help="task scene for every job (default: the bench's)")
    r.add_argument("--deadline-s", type=float, default=0.0, help="start no job after this many seconds (0: none)")
    r.add_argument("--scratch", default="")
    r.add_argument("--out", required=True)
    q = sub.add_parser("report")
    q.add_argument("--out", required=True)
    q.add_argument("--with", dest="with_", nargs="*", default=[], help="other study folders whose v000 (the base) to pair with")
    a = p.parse_args()
    {"sample": cmd_sample, "make": cmd_make, "run": cmd_run, "report": cmd_report}[a.cmd](a)


if __name__ == "__main__":
    main()
