#!/usr/bin/env python3
"""Fit the command-response feed-forward (velocity_feedback.feedforward) to a calibration sweep.

Reads pmg_policy_sil summaries (summary.json: per seed and segment the command and the achieved
velocity, the mean over the last 60 % of the segment), keeps the walking segments no seed fell in,
leaves out a seed's segment more than UPSET off its command (a stumble, not a response; each is
printed), averages the seeds of each command, and fits per axis i (v_x, v_y, w, heading frame) by least squares

  v_i = (g+_i + k+_i c) u_i+ + (g-_i + k-_i c) u_i- + u_i sum_{j!=i} (m_ij |u_j| + s_ij u_j) + sum_{j!=i} d_ij u_j

with c the crouch [m]: the controller's standing height minus the command's height, the height floored
at the walking floor as the controller's shaper floors it while walking, both as each summary records
them (standing_height, walking_min_height; --standing-height / --walking-min-height for summaries
written before they were recorded). c is 0 for the upright sweeps; the crouched sweeps
config/policies/response_sweep_{7,8}.yaml walk at 0.66-0.78 m.

(include/pmg/controller/velocity_feedback.hpp, CommandResponseModel). Which terms an axis gets is
chosen by K-fold cross-validation over the commands of these summaries alone (SETS below), with the
one-standard-error rule (Hastie, Tibshirani & Friedman, The Elements of Statistical Learning, 7.10):
the set with the fewest coefficients whose cross-validated mean squared error is within one standard
error (over the folds) of the lowest one's, so that terms whose gain is within the noise stay out.
Evaluation scripts are never read here. Writes the YAML block to paste under velocity_feedback:, a
report of the cross-validated errors, and prints both. The report also splits each axis's cross-validated
error by regime (upright or crouched, and the command's sign on that axis), for the identity, the gains
alone (G) and the chosen set: a pooled error can hide a regime the chosen terms do not carry (crouched
backward walks, 28 of 358 commands of finetune_n24b/F0a's fit).

  python3 scripts/fit_command_response.py out/response/summary.json [more summaries] --out FILE.yaml \
      [--plot FIT.png] [--check HELD_OUT_SUMMARY.json ...]
"""
import argparse
import json
import sys

import numpy as np

AXES = ("vx", "vy", "wz")
# Term groups of an axis's model: G gains (always), M gain per magnitude, S gain per signed command,
# D drift, C gains per metre of crouch. The candidate sets, simplest first (of two with as many
# coefficients the earlier one is kept; without crouched sweeps the C columns are zero and never win).
_BASE_SETS = ("G", "G+M", "G+S", "G+D", "G+M+D", "G+S+D", "G+M+S+D")
SETS = _BASE_SETS + tuple(f"{g}+C" for g in _BASE_SETS)
# Validation ranges of CommandResponseModel (velocity_feedback.cpp).
GAIN_RANGE = (0.3, 3.0)
COUPLING_RANGE = (-3.0, 3.0)
DRIFT_RANGE = (-1.0, 1.0)
CROUCH_RANGE = (-10.0, 10.0)  # gain_*_per_crouch [1/m]
MIN_WALK = (0.05, 0.05, 0.1)  # a segment walks when some |u_i| is at least this


UPSET = 0.4  # a seed's segment this far from its command on some axis [m/s, rad/s] is an upset, not a response


def load(paths, standing_height=0.7645, walking_min_height=0.66):
    """Per seed, the walking segments without a fall or an upset; a command (v_x, v_y, w, crouch c [m]) is one
    sample (the mean of its seeds). U is n x 4, V n x 3. The crouch's standing height and walking floor are
    each summary's own, else the arguments; summaries that disagree are an error (one model, one loop)."""
    by_command = {}
    dropped = {"fall": 0, "upset": 0}
    seen = {}
    for p in paths:
        with open(p) as f:
            d = json.load(f)
        for key, fallback in (("standing_height", standing_height), ("walking_min_height", walking_min_height)):
            value = float(d.get(key, fallback))
            if seen.setdefault(key, (value, p))[0] != value:
                sys.exit(f"fit_command_response: {p}: {key} {value} m, but {seen[key][1]} has {seen[key][0]} m "
                         f"(fit one controller's calibration runs together)")
        standing_height, walking_min_height = seen["standing_height"][0], seen["walking_min_height"][0]
        fallen = {s["name"]: s.get("fallen", 0) for s in d["segments"]}
        commands = {s["name"]: tuple(float(s["command"][a]) for a in AXES)
                    + (round(max(0.0, standing_height - max(float(s["command"].get("height", standing_height)),
                                                            walking_min_height)), 4),)
                    for s in d["segments"]}
        for run in d["runs"]:
            for s in run["segments"]:
                u = commands[s["name"]]
                if all(abs(u[i]) < MIN_WALK[i] for i in range(3)):
                    continue
                v = [s["achieved"][a] for a in AXES]
                if fallen[s["name"]] > 0 or any(x is None for x in v):
                    dropped["fall"] += 1
                    continue
                if any(abs(v[i] - u[i]) > UPSET for i in range(3)):
                    dropped["upset"] += 1
                    print(f"# upset left out: {p} seed {run['seed']} {s['name']} command {u} achieved "
                          f"({v[0]:.3f}, {v[1]:.3f}, {v[2]:.3f})")
                    continue
                acc = by_command.setdefault(u, [np.zeros(3), 0])
                acc[0] += np.array(v, float)
                acc[1] += 1
    U = np.array([list(u) for u in by_command], float).reshape(-1, 4)
    V = np.array([acc[0] / acc[1] for acc in by_command.values()], float).reshape(-1, 3)
    return U, V, dropped


def features(U, i, groups):
    ui = U[:, i]
    cols = [np.maximum(ui, 0.0), np.minimum(ui, 0.0)]
    labels = [("gain_positive", None), ("gain_negative", None)]
    others = [j for j in range(3) if j != i]
    if "C" in groups.split("+"):
        cols += [np.maximum(ui, 0.0) * U[:, 3], np.minimum(ui, 0.0) * U[:, 3]]
        labels += [("gain_positive_per_crouch", None), ("gain_negative_per_crouch", None)]
    for g, name, col in (("M", "gain_per_magnitude", lambda j: ui * np.abs(U[:, j])),
                         ("S", "gain_per_command", lambda j: ui * U[:, j]),
                         ("D", "drift", lambda j: U[:, j])):
        if g in groups.split("+"):
            for j in others:
                cols.append(col(j))
                labels.append((name, j))
    return np.stack(cols, axis=1), labels


def fit(U, y, i, groups):
    X, labels = features(U, i, groups)
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    return coef, labels


def cv_folds(n, i, folds):
    """The folds over @p n commands for axis @p i: a fixed shuffle, fold k every folds-th of it."""
    idx = np.random.default_rng(i).permutation(n)
    return [idx[k::folds] for k in range(folds)]


def cv_predict(U, y, i, groups, folds):
    """Cross-validated predictions: folds over commands (each sample is one command, its seeds
    averaged; cv_folds); every command predicted by the fit on the other folds."""
    idx = np.arange(len(y))
    pred = np.empty(len(y))
    for test in cv_folds(len(y), i, folds):
        train = np.setdiff1d(idx, test)
        coef, _ = fit(U[train], y[train], i, groups)
        X, _ = features(U[test], i, groups)
        pred[test] = X @ coef
    return pred


def select_one_se(U, y, i, preds, folds):
    """The one-standard-error rule over SETS' cross-validated predictions @p preds of axis @p i:
    the lowest mean squared error and its standard error over the folds; of the sets within that
    margin, the one with the fewest coefficients (SETS' order between equals). Returns
    (index of the chosen set, index of the lowest, the margin as an RMSE: sqrt(MSE_min + SE))."""
    fold_idx = cv_folds(len(y), i, folds)
    mse = np.array([np.mean((p - y) ** 2) for p in preds])
    lowest = int(np.argmin(mse))
    per_fold = [np.mean((preds[lowest][t] - y[t]) ** 2) for t in fold_idx]
    se = float(np.std(per_fold, ddof=1) / np.sqrt(folds))
    size = [features(U[:1], i, groups)[0].shape[1] for groups in SETS]
    within = [k for k in range(len(SETS)) if mse[k] <= mse[lowest] + se]
    chosen = min(within, key=lambda k: (size[k], k))
    return chosen, lowest, float(np.sqrt(mse[lowest] + se))


def rmse(e):
    return float(np.sqrt(np.mean(np.asarray(e) ** 2)))


def regimes(U, i):
    """Axis @p i's regimes, where a pooled error hides what a user feels: upright or crouched (c > 0), and
    the command's sign on this axis (|u_i| at least MIN_WALK[i]). Returns [(label, boolean mask)]."""
    crouched = U[:, 3] > 0.0
    out = []
    for posture, pm in (("upright", ~crouched), ("crouched", crouched)):
        for sign, sm in (("+", U[:, i] >= MIN_WALK[i]), ("-", U[:, i] <= -MIN_WALK[i])):
            out.append((f"{posture} {sign}", pm & sm))
    return out


def regime_line(axis, U, y, i, named_preds):
    """The report's per-regime line of axis @p i: for each (name, cross-validated prediction) the RMSE
    over each regime's commands (regimes()), and each regime's count; '-' for a regime without one."""
    cells = []
    for label, m in regimes(U, i):
        errs = "/".join(f"{rmse(p[m] - y[m]):.4f}" if m.any() else "-" for _, p in named_preds)
        cells.append(f"{label} {errs} ({int(m.sum())})")
    return (f"# {axis} per regime, cross-validated RMSE " + "/".join(n for n, _ in named_preds)
            + " (commands): " + " | ".join(cells))


def plot(path, U, V, cv_pred, check, block):
    """Per axis: achieved against predicted, the identity (v = u) in grey, the model's
    cross-validated predictions in colour, and held-out evaluation segments (--check) as crosses. With
    crouched commands a fourth panel: v_x achieved / commanded against the crouch, forward and backward
    walks (|v_x| >= 0.15 m/s) apart, with the fitted gains g + k c."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    units = ("v_x [m/s]", "v_y [m/s]", "yaw rate [rad/s]")
    crouched = bool(np.any(U[:, 3] > 0.0))
    fig, axs = plt.subplots(1, 4 if crouched else 3, figsize=(20 if crouched else 15, 5))
    for i, ax in enumerate(axs[:3]):
        y = V[:, i]
        ax.scatter(U[:, i], y, s=10, c="0.7", label=f"identity v = u (RMSE {rmse(U[:, i] - y):.3f})")
        ax.scatter(cv_pred[i], y, s=10, c="C0", label=f"model, cross-validated (RMSE {rmse(cv_pred[i] - y):.3f})")
        if check is not None:
            Uc, Vc, pc = check
            ax.scatter(Uc[:, i], Vc[:, i], marker="x", c="0.4", label=f"held out, identity (RMSE {rmse(Uc[:, i] - Vc[:, i]):.3f})")
            ax.scatter(pc[:, i], Vc[:, i], marker="x", c="C3", label=f"held out, model (RMSE {rmse(pc[:, i] - Vc[:, i]):.3f})")
        lo, hi = ax.get_xlim()
        ax.plot([lo, hi], [lo, hi], "k--", lw=0.8)
        ax.set_xlabel(f"predicted {units[i]}")
        ax.set_ylabel(f"achieved {units[i]}")
        ax.set_title(AXES[i])
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    if crouched:
        ax = axs[3]
        e = block["vx"]
        c_line = np.linspace(0.0, U[:, 3].max(), 20)
        for sign, name, colour in ((1, "positive", "C0"), (-1, "negative", "C3")):
            sel = sign * U[:, 0] >= 0.15
            ax.scatter(U[sel, 3], V[sel, 0] / U[sel, 0], s=10, c=colour, alpha=0.6,
                       label=f"{'forward' if sign > 0 else 'backward'} walks ({int(sel.sum())})")
            ax.plot(c_line, e[f"gain_{name}"] + e[f"gain_{name}_per_crouch"] * c_line, colour, lw=2,
                    label=f"g {e[f'gain_{name}']:.2f} {e[f'gain_{name}_per_crouch']:+.2f} c [1/m]")
        ax.axhline(1.0, color="k", ls="--", lw=0.8)
        ax.set_xlabel("crouch c: standing height - walking height [m]")
        ax.set_ylabel("v_x achieved / commanded [-]")
        ax.set_title("vx gain against the crouch")
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    fig.suptitle("Command-response model: achieved against predicted, per walking command (heading frame)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def predict(block, U):
    out = np.zeros((len(U), 3))
    for i, a in enumerate(AXES):
        e = block[a]
        c = U[:, 3]
        gain = np.where(U[:, i] >= 0.0, e["gain_positive"] + e.get("gain_positive_per_crouch", 0.0) * c,
                        e["gain_negative"] + e.get("gain_negative_per_crouch", 0.0) * c)
        drift = np.zeros(len(U))
        for j in range(3):
            if j == i:
                continue
            gain = gain + e["gain_per_magnitude"][j] * np.abs(U[:, j]) + e["gain_per_command"][j] * U[:, j]
            drift += e["drift"][j] * U[:, j]
        out[:, i] = gain * U[:, i] + drift
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summaries", nargs="+")
    ap.add_argument("--out", required=True, help="YAML block (feedforward:) to write")
    ap.add_argument("--folds", type=int, default=6)
    ap.add_argument("--max-correction", default="0.15,0.1,0.15",
                    help="the bound written into the block: v_x, v_y [m/s], w [rad/s] (the shipped one, chosen on tuning runs)")
    ap.add_argument("--standing-height", type=float, default=0.7645,
                    help="for summaries without standing_height: the controller's standing height [m], the crouch's "
                         "zero (the policy configs': the squat clip's neutral pelvis height, 0.7645)")
    ap.add_argument("--walking-min-height", type=float, default=0.66,
                    help="for summaries without walking_min_height: the controller's commands.walking_min_height [m] "
                         "(0: off): a walk commanded lower walks there")
    ap.add_argument("--plot", default=None, help="write achieved-against-predicted scatter plots here (PNG)")
    ap.add_argument("--check", nargs="*", default=None,
                    help="held-out summaries (feed-forward off) to report the model's error on; never used to fit")
    args = ap.parse_args()
    U, V, dropped = load(args.summaries, args.standing_height, args.walking_min_height)
    if len(U) < 3 * args.folds:
        sys.exit(f"fit_command_response: {len(U)} usable walking commands in {args.summaries}; need at least {3 * args.folds}")
    crouched = int(np.count_nonzero(U[:, 3] > 0.0))
    report = [f"# {len(U)} walking commands, {crouched} of them crouched (seed segments left out: {dropped['fall']} with a fall, {dropped['upset']} upsets "
              f"more than {UPSET} off their command), {args.folds}-fold cross-validation over commands",
              "# axis: RMSE of the identity (v = u) | of each term set (G gains, M per magnitude, S per signed command, D drift, "
              "C gains per crouch), "
              "cross-validated [m/s or rad/s]; the chosen set: the fewest coefficients within one standard error of the lowest"]
    block = {}
    cv_best = []
    for i, a in enumerate(AXES):
        y = V[:, i]
        ident = rmse(U[:, i] - y)
        preds = [cv_predict(U, y, i, groups, args.folds) for groups in SETS]
        scores = [rmse(p - y) for p in preds]
        best, lowest, margin = select_one_se(U, y, i, preds, args.folds)
        cv_best.append(preds[best])
        coef, labels = fit(U, y, i, SETS[best])
        report.append(f"# {a}: identity {ident:.4f} | " + " | ".join(f"{SETS[k]} {scores[k]:.4f}" for k in range(len(SETS)))
                      + f"  (lowest {SETS[lowest]}; within one standard error: <= {margin:.4f})  -> {SETS[best]}")
        report.append(regime_line(a, U, y, i, [("identity", U[:, i]), ("G", preds[0]), (f"chosen {SETS[best]}", preds[best])]))
        entry = {"gain_positive": 1.0, "gain_negative": 1.0, "gain_per_magnitude": [0.0] * 3,
                 "gain_per_command": [0.0] * 3, "drift": [0.0] * 3,
                 "gain_positive_per_crouch": 0.0, "gain_negative_per_crouch": 0.0}
        for c, (name, j) in zip(coef, labels):
            if j is None:
                entry[name] = float(np.clip(c, *(CROUCH_RANGE if name.endswith("_per_crouch") else GAIN_RANGE)))
            else:
                entry[name][j] = float(np.clip(c, *(DRIFT_RANGE if name == "drift" else COUPLING_RANGE)))
        block[a] = entry
    mc = [float(x) for x in args.max_correction.split(",")]
    lines = ["feedforward:", "  enabled: true"]
    for a in AXES:
        e = block[a]
        fmt = lambda xs: "[" + ", ".join(f"{x:.3f}" for x in xs) + "]"  # noqa: E731
        lines.append(f"  {a}: {{gain_positive: {e['gain_positive']:.3f}, gain_negative: {e['gain_negative']:.3f}, "
                     f"gain_per_magnitude: {fmt(e['gain_per_magnitude'])}, gain_per_command: {fmt(e['gain_per_command'])}, "
                     f"drift: {fmt(e['drift'])}, gain_positive_per_crouch: {e['gain_positive_per_crouch']:.3f}, "
                     f"gain_negative_per_crouch: {e['gain_negative_per_crouch']:.3f}}}")
    lines.append(f"  max_correction: [{mc[0]}, {mc[1]}, {mc[2]}]")
    text = "\n".join(report + lines) + "\n"
    with open(args.out, "w") as f:
        f.write(text)
    print(text, end="")
    check = None
    if args.check:
        Uc, Vc, _ = load(args.check, args.standing_height, args.walking_min_height)
        check = (Uc, Vc, predict(block, Uc))
        for i, a in enumerate(AXES):
            print(f"# held out ({len(Uc)} commands): {a} RMSE identity {rmse(Uc[:, i] - Vc[:, i]):.4f}, "
                  f"model {rmse(check[2][:, i] - Vc[:, i]):.4f}")
    if args.plot:
        plot(args.plot, U, V, cv_best, check, block)


if __name__ == "__main__":
    main()
