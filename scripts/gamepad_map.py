#!/usr/bin/env python3
"""Draws the button map of pmg_gamepad: a game controller outline (SDL GameController layout,
Xbox-style) with every control labelled with its function -> docs/img/gamepad_map.png.

The mode bindings, speeds and steps are read from the gamepad config (config/teleop/gamepad.yaml),
so the picture follows the config it documents:

    scripts/gamepad_map.py [--config config/teleop/gamepad.yaml] [--out docs/img/gamepad_map.png]
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle, FancyBboxPatch, Ellipse, Polygon  # noqa: E402
import yaml  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Short labels of SDL's control names.
SHORT = {
    "a": "A", "b": "B", "x": "X", "y": "Y", "back": "Back", "guide": "Guide", "start": "Start",
    "leftstick": "L3", "rightstick": "R3", "leftshoulder": "LB", "rightshoulder": "RB",
    "dpup": "↑", "dpdown": "↓", "dpleft": "←", "dpright": "→", "lefttrigger": "LT", "righttrigger": "RT",
}
MODE_TEXT = {
    "estop": "E-STOP: damping, latched",
    "stand": "STAND (soft stand)",
    "walk": "WALK (active: PMG / policy)",
    "damping": "DAMPING",
    "reset": "RESET (damping → passive), re-arm e-stop",
    "neutral_posture": "neutral posture",
}
RED, BLUE, GREEN, GREY = "#c0392b", "#1f5fa8", "#23803a", "#555555"


def chord(binding):
    return " + ".join(SHORT.get(c, c) for c in binding)


def load(path):
    with open(path) as f:
        cfg = yaml.safe_load(f) or {}
    s, p, b = cfg.get("sticks", {}), cfg.get("posture", {}), cfg.get("buttons", {})
    defaults = {
        "estop": ["lefttrigger", "b"], "stand": ["lefttrigger", "dpup"], "walk": ["rightshoulder", "x"],
        "damping": ["back"], "reset": ["lefttrigger", "start"], "neutral_posture": ["righttrigger", "y"],
    }
    bind = {k: b.get(k, v) for k, v in defaults.items()}
    return s, p, bind, b.get("mode_layer", "lefttrigger"), b.get("pitch_layer", "righttrigger")


def roles(bind, mode_layer, pitch_layer):
    """Function texts per control: every binding a control takes part in."""
    out = {}
    for name, binding in bind.items():
        color = RED if name in ("estop", "damping") else (GREEN if name in ("stand", "walk", "reset") else BLUE)
        for c in binding:
            others = [x for x in binding if x != c]
            prefix = ("with " + chord(others) + ": ") if others else ""
            out.setdefault(c, []).append((prefix + MODE_TEXT[name], color))
    out.setdefault(mode_layer, []).insert(0, ("held = mode layer (d-pad off the posture)", GREY))
    out.setdefault(pitch_layer, []).insert(0, ("held = pitch layer (d-pad ↑/↓ = pitch)", GREY))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=os.path.join(ROOT, "config/teleop/gamepad.yaml"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs/img/gamepad_map.png"))
    args = ap.parse_args()
    sticks, post, bind, mode_layer, pitch_layer = load(args.config)
    r = roles(bind, mode_layer, pitch_layer)
    vx, vy, wz = (sticks.get(k, {}).get("max", d) for k, d in (("vx", 0.6), ("vy", 0.3), ("wz", 0.8)))
    hs, hr = post.get("height_step", 0.02), post.get("height_rate", 0.1)
    ps, rs = post.get("pitch_step", 0.05), post.get("roll_step", 0.05)
    hrange = post.get("height_range", [0.55, 0.8])
    prange = post.get("pitch_range", [-0.2, 0.5])
    rrange = post.get("roll_range", [-0.2, 0.2])

    fig, ax = plt.subplots(figsize=(16, 9.4))
    ax.set_xlim(-13, 13)
    ax.set_ylim(-7.2, 7.0)
    ax.set_aspect("equal")
    ax.axis("off")

    body = "#e9ecef"
    edge = "#343a40"
    # Body: a rounded centre and two grips.
    ax.add_patch(Ellipse((-2.9, -1.3), 3.4, 5.0, angle=-25, fc=body, ec=edge, lw=2, zorder=1))
    ax.add_patch(Ellipse((2.9, -1.3), 3.4, 5.0, angle=25, fc=body, ec=edge, lw=2, zorder=1))
    ax.add_patch(FancyBboxPatch((-3.9, -0.9), 7.8, 3.1, boxstyle="round,pad=0.3,rounding_size=1.2", fc=body, ec=edge,
                                lw=2, zorder=1))
    ax.add_patch(Ellipse((-2.9, -1.3), 3.3, 4.9, angle=-25, fc=body, ec="none", zorder=2))
    ax.add_patch(Ellipse((2.9, -1.3), 3.3, 4.9, angle=25, fc=body, ec="none", zorder=2))
    ax.add_patch(FancyBboxPatch((-3.85, -0.85), 7.7, 3.0, boxstyle="round,pad=0.3,rounding_size=1.2", fc=body,
                                ec="none", zorder=2))

    def button(xy, text, radius=0.32, fc="white"):
        ax.add_patch(Circle(xy, radius, fc=fc, ec=edge, lw=1.5, zorder=3))
        ax.text(xy[0], xy[1], text, ha="center", va="center", fontsize=10, fontweight="bold", zorder=4)

    # Shoulders and triggers (drawn above the body, as seen from the front/top).
    for sx, lb, lt in ((-1, "LB", "LT"), (1, "RB", "RT")):
        ax.add_patch(FancyBboxPatch((sx * 2.9 - 1.0, 2.75), 2.0, 0.45, boxstyle="round,pad=0.05,rounding_size=0.2",
                                    fc="#ced4da", ec=edge, lw=1.5, zorder=3))
        ax.text(sx * 2.9, 2.975, lb, ha="center", va="center", fontsize=10, fontweight="bold", zorder=4)
        ax.add_patch(FancyBboxPatch((sx * 2.9 - 0.7, 3.45), 1.4, 0.8, boxstyle="round,pad=0.05,rounding_size=0.3",
                                    fc="#adb5bd", ec=edge, lw=1.5, zorder=3))
        ax.text(sx * 2.9, 3.85, lt, ha="center", va="center", fontsize=10, fontweight="bold", zorder=4)
    # Sticks.
    ls, rsk = (-2.6, 0.9), (1.3, -0.75)
    for xy, name in ((ls, "L"), (rsk, "R")):
        ax.add_patch(Circle(xy, 0.72, fc="#adb5bd", ec=edge, lw=1.5, zorder=3))
        ax.add_patch(Circle(xy, 0.45, fc="#6c757d", ec=edge, lw=1, zorder=4))
        ax.text(xy[0], xy[1], name, ha="center", va="center", color="white", fontsize=10, fontweight="bold", zorder=5)
    # D-pad.
    dp = (-1.3, -0.75)
    ax.add_patch(FancyBboxPatch((dp[0] - 0.22, dp[1] - 0.7), 0.44, 1.4, boxstyle="round,pad=0.02", fc="#495057",
                                ec=edge, zorder=3))
    ax.add_patch(FancyBboxPatch((dp[0] - 0.7, dp[1] - 0.22), 1.4, 0.44, boxstyle="round,pad=0.02", fc="#495057",
                                ec=edge, zorder=3))
    for (dx, dy), t in (((0, 0.47), "↑"), ((0, -0.47), "↓"), ((-0.47, 0), "←"), ((0.47, 0), "→")):
        ax.text(dp[0] + dx, dp[1] + dy, t, ha="center", va="center", color="white", fontsize=9, zorder=4)
    # Face buttons.
    fb = (2.6, 0.9)
    face = {"y": (fb[0], fb[1] + 0.62), "x": (fb[0] - 0.62, fb[1]), "b": (fb[0] + 0.62, fb[1]), "a": (fb[0], fb[1] - 0.62)}
    colors = {"a": "#8fd19e", "b": "#f1948a", "x": "#85c1e9", "y": "#f9e79f"}
    for k, xy in face.items():
        button(xy, SHORT[k], fc=colors[k])
    # Centre buttons.
    centre = {"back": (-0.85, 1.0), "start": (0.85, 1.0), "guide": (0.0, 1.75)}
    for k, xy in centre.items():
        button(xy, {"back": "◁", "start": "▷", "guide": "G"}[k], radius=0.25)

    def label(anchor, text_xy, lines, ha, via=None):
        pts = [anchor] + ([via] if via else []) + [text_xy]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], color=GREY, lw=1, zorder=6)
        y = text_xy[1] + 0.23 * (len(lines) - 1)
        dx = 0.15 if ha == "left" else (-0.15 if ha == "right" else 0.0)
        for i, (t, c) in enumerate(lines):
            ax.text(text_xy[0] + dx, y - 0.46 * i, t, ha=ha, va="center", fontsize=10.5, color=c,
                    fontweight="bold" if i == 0 else "normal")

    def lines(control, title):
        return [(title, "black")] + (r.get(control) or [("unused", GREY)])

    L, R = -5.2, 5.2
    label((-3.6, 3.85), (L, 5.4), lines("lefttrigger", "LT (left trigger)"), "right")
    label((-3.9, 2.97), (L, 3.75), lines("leftshoulder", "LB"), "right")
    label((-3.3, 1.0), (L, 1.85), [("Left stick", "black"), (f"↑/↓  forward / back  vx  ±{vx:g} m/s", BLUE),
                                   (f"←/→  left / right  vy  ±{vy:g} m/s (left +)", BLUE)], "right")
    dpad_lines = [("D-pad (posture set points)", "black"),
                  (f"↑/↓  height ±{hs * 100:g} cm per press, {hr:g} m/s held  [{hrange[0]:g}, {hrange[1]:g}] m", BLUE),
                  (f"with {SHORT[pitch_layer]}: ↑/↓  pitch ±{ps:g} rad  [{prange[0]:g}, {prange[1]:g}] rad", BLUE),
                  (f"←/→  roll ∓{rs:g} rad (lean left / right)  [{rrange[0]:g}, {rrange[1]:g}] rad", BLUE)]
    for name in ("stand", "estop", "walk", "damping", "reset"):
        b = bind[name]
        d = [c for c in b if c.startswith("dp")]
        if d:
            others = [c for c in b if c not in d]
            dpad_lines.append((("with " + chord(others) + ": " if others else "") + chord(d) + " = " + MODE_TEXT[name], GREEN))
    label((-2.0, -0.75), (L, -0.6), dpad_lines, "right")
    # Back and Start: labels above the controller (their lines go straight up, clear of the sticks).
    def wrapped(control, title):  # "with LT: RESET (damping → passive), re-arm" on two lines
        ls = lines(control, title)
        out = ls[:1]
        for t, c in ls[1:]:
            head, _, tail = t.partition(" (")
            paren, _, rest = tail.partition("), ")
            out += [(head, c)] + ([("(" + paren + (")" if rest else ""), c)] if tail else []) + ([(rest, c)] if rest else [])
        return out

    top = 5.3
    label((centre["back"][0], centre["back"][1] + 0.25), (centre["back"][0], top), wrapped("back", "Back (select)"),
          "right", via=(centre["back"][0], top))
    label((centre["start"][0], centre["start"][1] + 0.25), (centre["start"][0], top), wrapped("start", "Start"), "left",
          via=(centre["start"][0], top))
    label((3.6, 3.85), (R, 5.4), lines("righttrigger", "RT (right trigger)"), "left")
    label((3.9, 2.97), (R, 3.75), lines("rightshoulder", "RB"), "left")
    label((face["x"][0], face["x"][1] + 0.32), (R, 2.55), lines("x", "X"), "left", via=(face["x"][0], 2.4))
    label((face["y"][0] + 0.3, face["y"][1] + 0.08), (R, 1.45), lines("y", "Y"), "left")
    label((face["b"][0] + 0.32, face["b"][1]), (R, 0.35), lines("b", "B"), "left")
    label((face["a"][0], face["a"][1] - 0.32), (R, -0.75), lines("a", "A"), "left")
    label((rsk[0] + 0.72, rsk[1]), (R, -1.9),
          [("Right stick", "black"), (f"←/→  yaw rate  wz  ±{wz:g} rad/s (left = counter-clockwise)", BLUE)], "left")

    # Chord table and the rules.
    rows = [(chord(bind[k]), MODE_TEXT[k]) for k in ("estop", "stand", "walk", "damping", "reset", "neutral_posture")]
    y0 = -4.3
    ax.text(-12.6, y0, "Mode chords (press edge; e-stop level-triggered)", fontsize=11.5, fontweight="bold")
    for i, (c, t) in enumerate(rows):
        color = RED if "DAMP" in t or "E-STOP" in t else (GREEN if t.isupper() or "STAND" in t or "WALK" in t or "RESET" in t else BLUE)
        ax.text(-12.4, y0 - 0.5 * (i + 1), c, fontsize=10.5, fontweight="bold", color=color)
        ax.text(-9.6, y0 - 0.5 * (i + 1), t, fontsize=10.5, color=color)
    notes = [
        "Sticks released → exactly 0 (dead zone, expo, slew limits).",
        "Controller lost (unplugged / no state 0.5 s) → velocity 0 at once,",
        "   one DAMPING request 1 s later.",
        "After a loss or e-stop: velocity waits for the sticks to centre.",
        "Unbound controls (" + ", ".join(SHORT.get(c, c) for c in ("a", "leftshoulder", "guide", "leftstick", "rightstick")
                                         if c not in r) + ") do nothing.",
        "E-stop: release the chord, then " + chord(bind["reset"]) + " to re-arm.",
        "After unitree_rl_lab (LT+B passive, LT+↑ fix stand, RB+X velocity)",
        "   and unitree_rl_gym deploy_real (select = damping).",
    ]
    ax.text(0.6, y0, "Rules", fontsize=11.5, fontweight="bold")
    for i, t in enumerate(notes):
        ax.text(0.8, y0 - 0.47 * (i + 1), t, fontsize=10.5, color="black")
    ax.text(0, 6.75, "pmg_gamepad button map (SDL GameController layout; " + os.path.relpath(args.config, ROOT) + ")",
            ha="center", fontsize=14, fontweight="bold")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    fig.savefig(args.out, dpi=110, bbox_inches="tight")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
