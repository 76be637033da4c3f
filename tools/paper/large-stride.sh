#!/usr/bin/env bash
# The paper's large strides on flat ground (§V-A, Fig. 2-4) with one command: builds
# stride-paper-large-stride if it is missing, runs the IK baseline and KKT-DDP for each stride
# length, plays the DDP motion's policy on the mock robot (stride-sim's node, lock-step), prints
# the table, writes the trajectories (CSV / JSON), the IK and DDP motions as LCM logs
# (stride_XXX/{ik,ddp}.lcmlog) and the plots (PNG) into --out DIR; the snapshot figures are frames
# of stride-viz in headless Chromium, or stick figures when there is no browser (the script says
# why). Other options go to the program (stride-paper-large-stride --help), e.g. --lengths 0.8 1.0;
# --integrator euler|rk4 picks the contact knots' integrator (default euler; README.md,
# "Integrator").
#   tools/paper/large-stride.sh --out build/paper/large_stride
set -euo pipefail
source "$(dirname "$0")/run_experiment.sh"
run_experiment large-stride.sh stride-paper-large-stride plot_large_stride.py large_stride "$@"
