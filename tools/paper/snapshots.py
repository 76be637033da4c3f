"""The paper's snapshot figures rendered by stride-viz's page in headless Chromium (issue 18).

A motion written as an LCM log by a paper program (--log, tools/paper/motion_log.hpp) is played by
`stride-viz --log`; tools/paper/snapshots.mjs takes a screenshot of the robot at each chosen time,
and this module composes them into one figure: a row per log, a column per time, a label under
each frame. Where no browser is present the plot scripts draw stick figures instead
(run_experiment.sh says why).

As a program, on any log a paper program wrote:
  snapshots.py --viewer STRIDE_VIZ --node-modules DIR --out PNG --times T [T ...]
               --row LABEL LOG [--row LABEL LOG ...] [--title TEXT] [--labels TEXT ...]
               [--view astronaut|stride]
"""
import argparse
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image  # Debian's python3-pil, which python3-matplotlib depends on
from plot_common import plt

HERE = os.path.dirname(os.path.abspath(__file__))

# How each experiment frames its robot (snapshots.mjs, "camera"): seen from the side (the stick
# figures' sagittal plane, x to the right, z up), a little from the front and above so that both
# legs show. The astronaut turns about its CoM, which its log puts 1.2 m above the ground
# (astronaut_main.cpp): a square frame, fixed, 2.4 m high (head and soles are ~0.9 m from the
# CoM). The walker is followed: a portrait frame on its base, 1.9 m high (the robot is 1.57 m).
VIEWS = {
    "astronaut": {"tile": [300, 300],
                  "camera": {"direction": [0.35, -1.0, 0.18], "height": 2.4,
                             "target": [0.0, 0.0, 1.2]}},
    "stride": {"tile": [230, 330],
               "camera": {"direction": [0.35, -1.0, 0.22], "height": 1.9, "target": "base",
                          "target_z": 0.78}},
}

# A frame is blank when fewer than this fraction of its pixels differ from its background (its
# most common colour) by more than BLANK_CONTRAST in a channel. Measured in these views: the
# ground grid alone 0.6-0.9 %, a frame with the robot 2.5-7.5 % (its light grey faces are close to
# the background; its joints, feet and edges are not); a failed canvas is of one colour.
BLANK_FRACTION = 0.015
BLANK_CONTRAST = 0.25

# The figure: frames TILE_INCHES wide at DPI (~180 px; the screenshots, 230-300 px wide, are
# scaled down smoothly).
TILE_INCHES = 1.05
DPI = 170


class SnapshotError(RuntimeError):
    pass


def browser_missing(viewer, node_modules, chromium=None):
    """Why snapshots cannot be rendered here (None when they can)."""
    chromium = chromium or os.environ.get("CHROMIUM", "/usr/bin/chromium")
    if not (os.path.isfile(chromium) and os.access(chromium, os.X_OK)):
        return f"no Chromium at {chromium} (tools/install-deps.sh installs it)"
    if shutil.which("node") is None:
        return "no node on PATH (tools/install-deps.sh installs nodejs)"
    if not (viewer and os.access(viewer, os.X_OK)):
        return f"no stride-viz at {viewer} (build it: tools/build.sh)"
    page = os.path.join(os.path.dirname(viewer), "web", "dist", "index.html")
    if not os.path.isfile(page):
        return f"stride-viz's page is not built ({page})"
    if not os.path.isdir(os.path.join(node_modules or "", "playwright-core")):
        return f"no playwright-core in {node_modules} (the stride-viz-web target installs it)"
    return None


def blank_fraction(image):
    """The fraction of an RGB(A) image's pixels that stand out from its most common colour."""
    rgb = image[..., :3]
    flat = (rgb.reshape(-1, 3) * 255).round().astype(int)
    keys = flat[:, 0] * 65536 + flat[:, 1] * 256 + flat[:, 2]
    values, counts = np.unique(keys, return_counts=True)
    bg = values[counts.argmax()]
    background = [(bg >> 16) / 255.0, ((bg >> 8) & 255) / 255.0, (bg & 255) / 255.0]
    differs = (np.abs(rgb - np.asarray(background)) > BLANK_CONTRAST).any(axis=-1)
    return float(differs.mean())


def check_not_blank(path):
    image = plt.imread(path)
    fraction = blank_fraction(image)
    if fraction < BLANK_FRACTION:
        raise SnapshotError(f"{path}: blank ({100 * fraction:.2f} % of its pixels stand out from "
                            f"the background, at least {100 * BLANK_FRACTION:.0f} % expected)")
    return fraction


def render(viewer, node_modules, rows, times, out_png, labels=None, title=None, view="stride",
           work_dir=None):
    """Screenshots of each (label, log) row at `times` [s from the log's start], composed into
    out_png, and what the page showed (the page's snapshot() per frame) into out_png's name with
    .json. Returns snapshots.mjs's manifest. Raises SnapshotError when the renderer fails or a
    frame is blank."""
    setup = VIEWS[view]
    own_dir = work_dir is None
    work_dir = work_dir or tempfile.mkdtemp(prefix="stride-snapshots-")
    try:
        spec = {
            "viz": viewer,
            "node_modules": node_modules,
            "out_dir": work_dir,
            "rows": [{"label": label, "log": log} for label, log in rows],
            "times": list(times),
            "tile": setup["tile"],
            "scale": 1,
            "camera": setup["camera"],
        }
        spec_path = os.path.join(work_dir, "spec.json")
        with open(spec_path, "w") as f:
            json.dump(spec, f)
        done = subprocess.run(["node", os.path.join(HERE, "snapshots.mjs"), spec_path])
        if done.returncode != 0:
            raise SnapshotError(f"snapshots.mjs failed (exit {done.returncode})")
        with open(os.path.join(work_dir, "manifest.json")) as f:
            manifest = json.load(f)
        for row in manifest["rows"]:
            for frame in row["frames"]:
                frame["ink"] = check_not_blank(frame["png"])
        compose(manifest, out_png, labels or [f"{t:.2f} s" for t in times], title)
        check_not_blank(out_png)
        # What the page showed at each frame (stamp, joint angles read back from the drawn robot,
        # planned forces, camera), beside the figure: the tests check it against the logs.
        shown = {"figure": os.path.basename(out_png), "rows": [
            {"label": r["label"], "log": r["log"], "t0": r["t0"],
             "frames": [{k: v for k, v in f.items() if k != "png"} for f in r["frames"]]}
            for r in manifest["rows"]]}
        with open(os.path.splitext(out_png)[0] + ".json", "w") as f:
            json.dump(shown, f, indent=1)
        return manifest
    finally:
        if own_dir:
            shutil.rmtree(work_dir, ignore_errors=True)


def compose(manifest, out_png, labels, title):
    """One figure: a row per log (its label on the left), a frame per time, labels underneath."""
    rows = manifest["rows"]
    cols = max(len(r["frames"]) for r in rows)
    first = plt.imread(rows[0]["frames"][0]["png"])
    h, w = first.shape[:2]
    tile_w = TILE_INCHES
    tile_h = tile_w * h / w
    label_h = 0.34 if any("\n" in s for s in labels) else 0.22
    left = 0.3 if any(r["label"] for r in rows) else 0.05
    top = 0.5 if title else 0.15
    fig_w = left + cols * tile_w + 0.05
    fig_h = top + len(rows) * (tile_h + label_h) + 0.05
    fig = plt.figure(figsize=(fig_w, fig_h))
    for r, row in enumerate(rows):
        y = fig_h - top - (r + 1) * (tile_h + label_h) + label_h
        for i, frame in enumerate(row["frames"]):
            x = left + i * tile_w
            ax = fig.add_axes([x / fig_w, y / fig_h, tile_w / fig_w, tile_h / fig_h])
            ax.imshow(plt.imread(frame["png"]), interpolation="lanczos")
            ax.set_xticks([])
            ax.set_yticks([])
            for spine in ax.spines.values():
                spine.set_color("#c0c6cc")
            if i < len(labels):
                ax.set_xlabel(labels[i], fontsize=7, labelpad=2)
        if row["label"]:
            fig.text(0.5 * left / fig_w, (y + 0.5 * tile_h) / fig_h, row["label"], rotation=90,
                     ha="center", va="center", fontsize=9, fontweight="bold")
    if title:
        scales = {f["snapshot"].get("force_scale") for r in rows for f in r["frames"]}
        scales.discard(None)
        caption = "stride-viz in headless Chromium"
        if scales:
            caption += "; blue arrows: planned contact forces, " + ", ".join(sorted(scales))
        fig.text(0.5, 1 - 0.16 / fig_h, title, ha="center", va="top", fontsize=10)
        fig.text(0.5, 1 - 0.36 / fig_h, caption, ha="center", va="top", fontsize=7,
                 color="#5f6b76")
    # 128 colours: the figure is a few flat colours and the grid's greys, and a palette PNG is a
    # third of the size of a full-colour one (~0.5 MB for the strides' 24 frames) with no visible
    # change.
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI)
    plt.close(fig)
    buffer.seek(0)
    image = Image.open(buffer).convert("RGB")
    image.quantize(colors=128, method=Image.Quantize.MEDIANCUT,
                   dither=Image.Dither.NONE).save(out_png, optimize=True)


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--viewer", required=True, help="stride-viz")
    p.add_argument("--node-modules", required=True, help="node_modules with playwright-core")
    p.add_argument("--out", required=True, help="the figure (PNG)")
    p.add_argument("--times", type=float, nargs="+", required=True,
                   help="seconds from the log's start")
    p.add_argument("--labels", nargs="+", help="one per time (default: the time)")
    p.add_argument("--row", nargs=2, action="append", metavar=("LABEL", "LOG"), required=True)
    p.add_argument("--title")
    p.add_argument("--view", choices=sorted(VIEWS), default="stride")
    p.add_argument("--manifest", help="also write the frames' snapshots (JSON) here")
    p.add_argument("--keep", help="keep the frames in this folder")
    a = p.parse_args(argv)
    why = browser_missing(a.viewer, a.node_modules)
    if why:
        print(f"snapshots.py: {why}", file=sys.stderr)
        return 77
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    try:
        manifest = render(a.viewer, a.node_modules, a.row, a.times, a.out, a.labels, a.title,
                          a.view, work_dir=a.keep)
    except SnapshotError as e:
        print(f"snapshots.py: {e}", file=sys.stderr)
        return 1
    if a.manifest:
        with open(a.manifest, "w") as f:
            json.dump(manifest, f, indent=1)
    print(f"snapshots.py: wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
