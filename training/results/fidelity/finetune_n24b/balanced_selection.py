#!/usr/bin/env python3
"""The feed-forward's term choice on the balanced cross-validated error instead of the pooled one (an analysis of
2026-12-04, not the shipped rule; README.md "F0c and F0d").

For each axis: the one-standard-error rule of scripts/fit_command_response.py, applied to the mean over six regimes
(upright or crouched x forward, backward or not moving on the axis) of each regime's cross-validated mean squared
error, with the standard error over the same folds. Prints the pooled rule's choice, the balanced one's, and the
per-regime errors of the identity and of both choices. Reads only the calibration runs of the feed-forward fit.

  python3 training/results/fidelity/finetune_n24b/balanced_selection.py \
      training/results/fidelity/finetune_n24b/F0a/eval training/results/fidelity/finetune_n24b/F0d/eval
"""
import glob
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../../scripts"))
import fit_command_response as fcr  # noqa: E402


def groups(U, i):
    """fit_command_response's four regimes of axis @p i, plus the commands still on it, upright and crouched."""
    crouched = U[:, 3] > 0.0
    still = np.abs(U[:, i]) < fcr.MIN_WALK[i]
    return [m for m in [m for _, m in fcr.regimes(U, i)] + [still & ~crouched, still & crouched] if m.any()]


def balanced_mse(p, y, masks, within=None):
    vals = [np.mean((p[m] - y[m]) ** 2) for m in (masks if within is None else [m & within for m in masks]) if m.any()]
    return float(np.mean(vals))


def main():
    folds = 6
    for run in sys.argv[1:]:
        U, V, _ = fcr.load(sorted(glob.glob(os.path.join(run, "feedforward/calibration_*/summary.json"))))
        print(f"{run}: {len(U)} commands")
        for i, a in enumerate(fcr.AXES):
            y = V[:, i]
            preds = [fcr.cv_predict(U, y, i, g, folds) for g in fcr.SETS]
            pooled, _, _ = fcr.select_one_se(U, y, i, preds, folds)
            masks = groups(U, i)
            bal = np.array([balanced_mse(p, y, masks) for p in preds])
            lowest = int(np.argmin(bal))
            per_fold = []
            for t in fcr.cv_folds(len(y), i, folds):
                m = np.zeros(len(y), bool)
                m[t] = True
                per_fold.append(balanced_mse(preds[lowest], y, masks, m))
            se = float(np.std(per_fold, ddof=1) / np.sqrt(folds))
            size = [fcr.features(U[:1], i, g)[0].shape[1] for g in fcr.SETS]
            chosen = min((k for k in range(len(fcr.SETS)) if bal[k] <= bal[lowest] + se), key=lambda k: (size[k], k))
            print(f"  {a}: pooled rule -> {fcr.SETS[pooled]}; balanced: lowest {fcr.SETS[lowest]} "
                  f"{np.sqrt(bal[lowest]):.4f}, margin {np.sqrt(bal[lowest] + se):.4f} -> {fcr.SETS[chosen]}")
            print("    " + fcr.regime_line(a, U, y, i, [("identity", U[:, i]), ("pooled", preds[pooled]),
                                                        ("balanced", preds[chosen])]))


if __name__ == "__main__":
    main()
