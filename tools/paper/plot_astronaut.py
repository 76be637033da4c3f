#!/usr/bin/env python3
"""Plots of the astronaut reorientation (paper §V-B, Fig. 5-6) from stride-paper-astronaut's output.

Usage: plot_astronaut.py DIR [--viewer STRIDE_VIZ --node-modules DIR]
(reads DIR/{trajectory,frames}.csv, summary.json, skeleton.json; writes
DIR/astronaut_{torques,pitch,snapshots,sagittal}.png). matplotlib (Debian python3-matplotlib).
With --viewer the snapshots are frames of stride-viz's page on DIR/session.lcmlog
(snapshots.py: headless Chromium); without, stick figures.
"""
import argparse
import json
import sys

import snapshots
from plot_common import plt, read_csv


def main(out, viewer=None, node_modules=None):
    traj = read_csv(f"{out}/trajectory.csv")
    frames = read_csv(f"{out}/frames.csv")
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    with open(f"{out}/skeleton.json") as f:
        segments = json.load(f)["segments"]
    t = traj["t"]
    taus = [k for k in traj if k.startswith("tau_")]

    # Fig. 6: joint torques (a kick, small corrections, braking). Torques are held over a knot.
    fig, axes = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True)
    for ax, kind in zip(axes, ("hip_pitch", "knee")):
        for k in taus:
            if k.endswith(kind):
                ax.step(t, traj[k], where="post", label=k[4:], lw=1.2)
        ax.set_ylabel(f"{kind} torque [Nm]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("Astronaut reorientation: joint torques (paper Fig. 6)")
    fig.tight_layout()
    fig.savefig(f"{out}/astronaut_torques.png", dpi=90)
    plt.close(fig)

    # Base pitch (unwrapped) with the waypoint goals, and the angular momentum.
    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    ax = axes[0]
    ax.plot(t, traj["pitch_deg"], label="plan: forward axis in the x-z plane", lw=1.5)
    ax.plot(t, traj["pitch_sum_deg"], label="plan: Σ y increments", lw=0.8, alpha=0.7)
    # Each window's goal at the end of what it committed (relative to the pitch it started from).
    wt = [summary["waypoints"][w["first"] + w["committed"] - 1]["t"] for w in summary["windows"]]
    ax.plot(wt, [w["goal_deg"] for w in summary["windows"]], "kx", ms=7,
            label="window goals (at commit)")
    ax.set_ylabel("base pitch [deg]")
    ax.set_yticks(range(-90, 361 + 90, 90))
    ax.axhline(360, color="tab:green", lw=0.8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.plot(t, traj["h_left_y"], label="left leg, y", lw=1)
    ax.plot(t, traj["h_right_y"], label="right leg, y", lw=1)
    ax.plot(t, traj["h_norm"], "k", label="whole body |h|", lw=1.5)
    ax.set_ylabel("angular momentum\nabout the CoM [kg m²/s]")
    ax.set_xlabel("time [s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle(f"Base pitch {summary['base_pitch_deg']:.0f}°, max |h| {summary['max_angular_momentum_norm']:.1e}")
    fig.tight_layout()
    fig.savefig(f"{out}/astronaut_pitch.png", dpi=90)
    plt.close(fig)

    # Fig. 5: the robot at 12 instants, side by side in time: frames of stride-viz's page when
    # a browser is there, else stick figures in the sagittal plane (x forward, z up).
    n = 12
    count = len(frames["t"])
    picks = [round(i * (count - 1) / (n - 1)) for i in range(n)]
    labels = [f"{frames['t'][k]:.2f} s\n{traj['pitch_deg'][k]:.0f}°" for k in picks]
    if viewer:
        snapshots.render(viewer, node_modules, [("", f"{out}/session.lcmlog")],
                         [frames["t"][k] for k in picks], f"{out}/astronaut_snapshots.png",
                         labels=labels, view="astronaut",
                         title="Astronaut reorientation, side view (base pitch under each frame)")
    else:
        stick_snapshots(frames, segments, picks, labels, f"{out}/astronaut_snapshots.png")
    sagittal(frames, segments, traj, count, f"{out}/astronaut_sagittal.png")
    print(f"  plots: {out}/astronaut_torques.png, astronaut_pitch.png, astronaut_snapshots.png "
          f"({'stride-viz' if viewer else 'stick figures'}), astronaut_sagittal.png")


def stick_snapshots(frames, segments, picks, labels, path):
    """Stick figures in the sagittal plane at `picks`, side by side."""
    spacing = 1.4
    fig, ax = plt.subplots(figsize=(13, 2.6))
    for i, k in enumerate(picks):
        dx = i * spacing
        for a, b in segments:
            color = "tab:red" if a.startswith("R_") or b.startswith("R_") else "tab:blue"
            if a in ("head", "chest") or b == "chest":
                color = "k"
            ax.plot([frames[f"{a}_x"][k] + dx, frames[f"{b}_x"][k] + dx],
                    [frames[f"{a}_z"][k], frames[f"{b}_z"][k]], color=color, lw=2,
                    solid_capstyle="round")
        ax.plot(frames["head_x"][k] + dx, frames["head_z"][k], "ko", ms=5)
        ax.text(dx, -1.05, labels[i], ha="center", fontsize=7)
    ax.set_aspect("equal")
    ax.set_ylim(-1.2, 1.0)
    ax.axis("off")
    ax.set_title("Astronaut reorientation, sagittal view (blue: left leg, red: right leg)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def sagittal(frames, segments, traj, count, path):
    """The stick figure at a few instants overlaid about the initial CoM (the body turning
    round), and the legs' shape loops (hip vs knee angle) that produce the rotation."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 5), gridspec_kw={"width_ratios": [1, 1.2]})
    n = 16
    picks = [round(i * (count - 1) / n) for i in range(n)]
    cmap = plt.get_cmap("viridis")
    for i, k in enumerate(picks):
        c = cmap(i / (n - 1))
        for a, b in segments:
            ax.plot([frames[f"{a}_x"][k], frames[f"{b}_x"][k]],
                    [frames[f"{a}_z"][k], frames[f"{b}_z"][k]], color=c, lw=1.5, alpha=0.8)
        ax.plot(frames["head_x"][k], frames["head_z"][k], "o", color=c, ms=4)
    ax.plot(0, 0, "k+", ms=10)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title("stick figure every 1/16 of the motion\n(dark → light), about the initial CoM",
                 fontsize=9)
    for side, color in (("L", "tab:blue"), ("R", "tab:red")):
        hip, knee = traj.get(f"q_{side}_hip_pitch"), traj.get(f"q_{side}_knee")
        if hip is not None and knee is not None:
            ax2.plot(hip, knee, color=color, lw=0.5, alpha=0.6, label=f"{side} leg")
    ax2.set_xlabel("hip pitch [rad]")
    ax2.set_ylabel("knee [rad]")
    ax2.set_title("leg shape loops (each closed loop turns the base)", fontsize=9)
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(usage=__doc__)
    parser.add_argument("dir")
    parser.add_argument("--viewer", help="stride-viz: snapshots from its page (else stick figures)")
    parser.add_argument("--node-modules", help="node_modules with playwright-core")
    args = parser.parse_args()
    try:
        main(args.dir, args.viewer, args.node_modules)
    except snapshots.SnapshotError as e:
        sys.exit(f"plot_astronaut.py: snapshots: {e}")
