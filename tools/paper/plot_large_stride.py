#!/usr/bin/env python3
"""Plots of the large strides (paper §V-A, Fig. 2-4) from stride-paper-large-stride's output.

Usage: plot_large_stride.py DIR [--viewer STRIDE_VIZ --node-modules DIR]
(reads DIR/summary.json, DIR/skeleton.json and, per stride,
DIR/stride_XXX/{trajectory,iterations,frames_ik,frames_ddp}.csv; writes, per stride,
DIR/large_stride_XXX_{grf,cost,snapshots}.png). matplotlib (Debian python3-matplotlib). With
--viewer the snapshots are frames of stride-viz's page on DIR/stride_XXX/{ik,ddp}.lcmlog
(snapshots.py: headless Chromium, the planned forces as arrows); without, stick figures.
"""
import argparse
import json
import sys

import snapshots
from plot_common import plt, read_csv


def plot_grf(traj, weight, title, path):
    """Fig. 3: left knee torque (top) and left-foot normal force (bottom), IK vs DDP."""
    t = traj["t"]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax1.plot(t, traj["ik_knee_L"], label="IK", color="tab:red")
    ax1.plot(t, traj["ddp_knee_L"], label="DDP", color="tab:blue")
    ax1.set_ylabel("left knee torque [Nm]")
    ax1.legend()
    ax1.grid(alpha=0.3)
    ax2.plot(t, traj["ik_fz_L"], label="IK", color="tab:red")
    ax2.plot(t, traj["ddp_fz_L"], label="DDP (plan)", color="tab:blue")
    if not all(v != v for v in traj["sim_fz_L"]):
        ax2.plot(t, traj["sim_fz_L"], label="DDP on the mock robot", color="tab:green", lw=0.8)
    ax2.plot(t, traj["fref_L_z"], label="centroidal reference", color="gray", ls="--", lw=0.8)
    ax2.axhline(weight, color="k", lw=0.6, ls=":", label="robot weight")
    ax2.set_ylabel("left foot normal force [N]")
    ax2.set_xlabel("t [s]")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_cost(it, groups, title, path):
    """Fig. 2: each cost group normalized by its value at the IK warm start (iteration 0)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for g in groups:
        v0 = it[g][0]
        if v0 <= 0:
            continue
        ax.plot(it["iteration"], [v / v0 for v in it[g]], label=g)
    ax.set_yscale("log")
    ax.set_xlabel("DDP iteration (0: IK warm start)")
    ax.set_ylabel("cost / cost at the IK trajectory")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def snapshot_samples(frames, count=12):
    """Fig. 4's instants: `count` samples evenly spaced over the motion."""
    n = len(frames["t"])
    return [round(i * (n - 1) / (count - 1)) for i in range(count)]


def plot_snapshots(frames_ik, frames_ddp, skeleton, title, path):
    """Fig. 4: sagittal stick figures, IK (top) and DDP (bottom), at evenly spaced instants."""
    names = skeleton["frames"]
    segs = skeleton["segments"]
    idx = snapshot_samples(frames_ddp)
    count = len(idx)
    fig, axes = plt.subplots(2, 1, figsize=(14, 5.5), sharex=True)
    for ax, frames, label, color in ((axes[0], frames_ik, "IK", "tab:red"),
                                     (axes[1], frames_ddp, "DDP", "tab:blue")):
        for j, k in enumerate(idx):
            shade = 0.35 + 0.65 * j / max(1, count - 1)
            for a, b in segs:
                xa, za = frames[names[a] + "_x"][k], frames[names[a] + "_z"][k]
                xb, zb = frames[names[b] + "_x"][k], frames[names[b] + "_z"][k]
                ax.plot([xa, xb], [za, zb], color=color, alpha=shade, lw=1.5)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_aspect("equal")
        ax.set_ylabel(f"{label}: z [m]")
    axes[1].set_xlabel("x [m]")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(out, viewer=None, node_modules=None):
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    with open(f"{out}/skeleton.json") as f:
        skeleton = json.load(f)
    groups = ["com", "feet", "forces", "torque", "posture", "contact"]
    for s in summary["strides"]:
        cm = round(100 * s["length_m"])
        d = f"{out}/stride_{cm:03d}"
        traj = read_csv(f"{d}/trajectory.csv")
        it = read_csv(f"{d}/iterations.csv")
        title = (f"{cm} cm stride: peak normal force IK {s['ik']['peak_normal_force_N']:.0f} N, "
                 f"DDP {s['ddp']['peak_normal_force_N']:.0f} N (weight {s['weight_N']:.0f} N)")
        plot_grf(traj, s["weight_N"], title, f"{out}/large_stride_{cm:03d}_grf.png")
        plot_cost(it, groups, f"{cm} cm stride: cost by DDP iteration",
                  f"{out}/large_stride_{cm:03d}_cost.png")
        frames_ddp = read_csv(f"{d}/frames_ddp.csv")
        path = f"{out}/large_stride_{cm:03d}_snapshots.png"
        if viewer:
            # The same instants as the stick figures, each motion's log in the page: IK above,
            # DDP below, the forces each plans drawn as arrows.
            times = [frames_ddp["t"][k] for k in snapshot_samples(frames_ddp)]
            snapshots.render(viewer, node_modules,
                             [("IK", f"{d}/ik.lcmlog"), ("DDP", f"{d}/ddp.lcmlog")], times, path,
                             title=f"{cm} cm stride: IK (top) and DDP (bottom)", view="stride")
        else:
            plot_snapshots(read_csv(f"{d}/frames_ik.csv"), frames_ddp, skeleton,
                           f"{cm} cm stride (sagittal view)", path)
    print(f"plots written to {out}/large_stride_*.png (snapshots: "
          f"{'stride-viz' if viewer else 'stick figures'})")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(usage=__doc__)
    parser.add_argument("dir", nargs="?", default=".")
    parser.add_argument("--viewer", help="stride-viz: snapshots from its page (else stick figures)")
    parser.add_argument("--node-modules", help="node_modules with playwright-core")
    args = parser.parse_args()
    try:
        main(args.dir, args.viewer, args.node_modules)
    except snapshots.SnapshotError as e:
        sys.exit(f"plot_large_stride.py: snapshots: {e}")
