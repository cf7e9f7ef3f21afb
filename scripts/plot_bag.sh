#!/usr/bin/env bash
# Plots and report.md of any bag of this project's topics (a run's, a replay's, an imported log):
#   scripts/plot_bag.sh BAG [--out DIR] [--topics TOPIC ...]
# BAG: a bag directory, a .mcap file or a run directory. Exit status: 0 drawn, 1 nothing to
# draw, 2 bad arguments or not a bag.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.plot_bag "$@"
