#!/usr/bin/env python3
"""Draws docs/img/architecture.png: the runtime of pmg_controller (threads, rates, hand-overs, the
HAL stack and the mode machine). Run from anywhere: python3 scripts/architecture_diagram.py"""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "img", "architecture.png")

fig, ax = plt.subplots(figsize=(16, 10.5))
ax.set_xlim(0, 160)
ax.set_ylim(0, 105)
ax.axis("off")

THREAD = "#dbe9f6"
QUEUE = "#fff2cc"
HAL = "#e2f0d9"
EXT = "#f2f2f2"
MODE = "#fbe5d6"


def box(x, y, w, h, text, color, size=9, bold_first=True, edge="#333333"):
    ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.4,rounding_size=1.2", fc=color, ec=edge, lw=1.2))
    lines = text.split("\n")
    if bold_first:
        ax.text(x + w / 2, y + h - 2.2, lines[0], ha="center", va="top", fontsize=size + 1, fontweight="bold")
        ax.text(x + w / 2, y + h - 5.4, "\n".join(lines[1:]), ha="center", va="top", fontsize=size, linespacing=1.35)
    else:
        ax.text(x + w / 2, y + h / 2, text, ha="center", va="center", fontsize=size, linespacing=1.35)


def arrow(x0, y0, x1, y1, text="", color="#333333", style="-|>", rad=0.0, dy=1.2, dx=0.0, size=8):
    ax.add_patch(FancyArrowPatch((x0, y0), (x1, y1), arrowstyle=style, mutation_scale=14, color=color, lw=1.4,
                                 connectionstyle=f"arc3,rad={rad}"))
    if text:
        ax.text((x0 + x1) / 2 + dx, (y0 + y1) / 2 + dy, text, ha="center", va="bottom", fontsize=size, color=color)


ax.text(80, 103, "pmg_controller at run time (ControllerApp, one Runner, one clock)", ha="center", va="top",
        fontsize=15, fontweight="bold")

# Command sources
box(2, 74, 30, 20, "LCM receive thread\nLcmCommandSource: PMG_VELOCITY,\nPOSTURE, MODE, VR_POSE; MAC,\nreplay, age, then raw bytes\nchecked by LcmCommandDecoder:\nrejects & counts, never throws", THREAD)
box(2, 53, 30, 16, "Command script\n(lockstep or --script)\none format: name, duration|t,\nvx vy wz pitch roll height, mode", EXT)
box(40, 80, 26, 11, "LatestValue<CommandSample>\nCommand u = u_d + u_s\n(height: optional)", QUEUE, size=8)
arrow(32, 84, 40, 85)
arrow(32, 61, 40, 81, rad=-0.2)

# Loop thread
box(72, 58, 44, 36,
    "100 Hz loop thread (Controller::tick)\n"
    "1 read   HAL state (+ supervisor mode), input\n"
    "         mode requests -> supervisor mailbox\n"
    "  teleop  VR headset -> command (if engaged)\n"
    "2 shape  CommandShaper: NaN/range/stale,\n"
    "         slew (height none <-> value too)\n"
    "3 generate  PMG generator (eqs. 4-12) + GCO\n"
    "         teleop arm IK replaces the arms\n"
    "         ReferenceRateLimiter <= 6 rad/s\n"
    "4 policy  ONNX actor (legs), limb separation\n"
    "5 write  LowCommand, TelemetryFrame\n"
    "returns TickStatus; noexcept, no allocation", THREAD, size=8.5)
arrow(66, 85, 72, 85)

# Telemetry
box(124, 74, 34, 20, "Telemetry publisher thread\nTelemetryPublisher\nPMG_STATE, PMG_TIMING\n-> LCM and the .lcmlog event log\n(timing p50/p99/max, drops counted)", THREAD)
box(124, 59, 34, 9, "SpscRing<TelemetryFrame, 1024>", QUEUE, size=8, bold_first=False)
arrow(116, 66, 124, 63, "frame / tick", dy=0.6)
arrow(141, 68, 141, 74)

# Hand-over to HAL
box(72, 42, 25, 8, "LatestValue<LowCommand>", QUEUE, size=8, bold_first=False)
box(104, 42, 25, 8, "LatestValue<LowState>", QUEUE, size=8, bold_first=False)
box(40, 42, 25, 8, "ModeRequestMailbox\n(e-stop never overwritten)", QUEUE, size=7.5, bold_first=False)
arrow(86, 58, 85, 50.8)
arrow(115, 50.8, 110, 58)
arrow(74, 60, 55, 50.8, rad=0.15)

# HAL thread and stack
box(34, 2, 124, 32, "", HAL)
ax.text(96, 32.5, "500 Hz HAL thread (HalRunner::cycle), stack built by makeHalStack()", ha="center", va="top",
        fontsize=10.5, fontweight="bold")
box(38, 5, 44, 21,
    "SafeBackend + SafetySupervisor\nthe only mode state machine\nwatchdogs (command, motors, IMU)\n"
    "envelope, fall (tilt/height), slew,\ntorque clamps; latched damping", MODE, size=8)
box(88, 5, 26, 21, "ZeroOffsetBackend\ncalibrated encoder\nzeros of the robot\nconfig (if any)", HAL, size=8)
box(120, 5, 34, 21, "backend\nMujocoBackend (SIL, 1 kHz)\nCanBackend (SocketCAN /\nUDP to pmg_sil)\nor a test's backend", EXT, size=8)
arrow(82, 15, 88, 15)
arrow(114, 15, 120, 15)
arrow(82, 42, 70, 26.8, "command", dx=4)
arrow(82, 23, 112, 42, "state + mode, fault", rad=-0.25, dy=-4, dx=6)
arrow(50, 42, 50, 26.8, "request", dx=-5)

# Mode machine inset
mx, my = 2, 8
ax.text(mx + 14, my + 16, "modes (pmg::Mode, LCM codes)", ha="center", fontsize=8.5, fontweight="bold")
states = {"passive 0": (mx + 2, my + 9), "soft stand 1": (mx + 16, my + 9), "active 2": (mx + 16, my + 1),
          "damping 3": (mx + 2, my + 1)}
for name, (x, y) in states.items():
    ax.add_patch(FancyBboxPatch((x, y), 11, 4.5, boxstyle="round,pad=0.2", fc=MODE, ec="#333333", lw=1.0))
    ax.text(x + 5.5, y + 2.25, name, ha="center", va="center", fontsize=7)
arrow(mx + 13.2, my + 11.2, mx + 16, my + 11.2, size=6)
arrow(mx + 21.5, my + 9, mx + 21.5, my + 5.5, size=6)
arrow(mx + 16, my + 3, mx + 13.2, my + 3, size=6)
arrow(mx + 7.5, my + 5.5, mx + 7.5, my + 9, size=6)
ax.text(mx + 14, my - 1.2, "request soft stand/active; fault or e-stop (3) -> damping;\nreset (4): damping -> passive",
        ha="center", va="top", fontsize=6.5)

fig.savefig(OUT, dpi=110, bbox_inches="tight")
print(OUT)
