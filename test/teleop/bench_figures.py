"""Shared check of the pmg_teleop_bench tests: every file a summary's "figures" entry names exists."""
import os


def missing_figure_files(out, figures):
    """Problems with summary.json's figures in folder @p out: one line per named file (event log,
    object track, scene, frame strip, trace plot) that is missing or under 1 kB."""
    problems = []
    for label, f in figures.items():
        for key in ("log", "objects", "scene", "strip", "trace"):
            p = f.get(key)
            if not p or not os.path.isfile(os.path.join(out, p)) or os.path.getsize(os.path.join(out, p)) < 1000:
                problems.append(f"figures.{label}.{key} = {p}: missing or empty")
    return problems
