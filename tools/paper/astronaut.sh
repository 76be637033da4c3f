#!/usr/bin/env bash
# The paper's astronaut reorientation (§V-B, Fig. 5-6) with one command: builds
# stride-paper-astronaut if it is missing, solves, prints the table, writes the trajectories
# (CSV / JSON), the motion as an LCM log (session.lcmlog) and the plots (PNG) into --out DIR; the
# snapshot figure is frames of stride-viz in headless Chromium, or stick figures when there is no
# browser (the script says why). Other options go to the program
# (stride-paper-astronaut --help), e.g. --knots 4500 --waypoints 36. One thread unless
# OMP_NUM_THREADS says otherwise (the README's timings are on one core). --integrator rk4|euler
# picks the knots' integrator (default rk4, whose knots conserve the momentum the experiment is
# about; --integrator euler is the paper's semi-implicit Euler: README.md, "Integrator").
#   tools/paper/astronaut.sh --out build/paper/astronaut
set -euo pipefail
source "$(dirname "$0")/run_experiment.sh"
run_experiment astronaut.sh stride-paper-astronaut plot_astronaut.py astronaut "$@"
