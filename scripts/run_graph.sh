#!/usr/bin/env bash
# Main job: run a scenario through the whole ROS 2 node graph, record everything to an MCAP
# bag, and print the alignment result.
#   scripts/run_graph.sh [--scenario NAME] [--out DIR] [--seed N] [--set KEY=VALUE ...]
#     [--real-time-factor R] [--timeout S] [--domain-id N]
# Exit status: 0 complete run; 1 incomplete (lost or foreign messages, cut short, a process
# failed, the bag repaired); 130/143 stopped by SIGINT/SIGTERM (every process stopped, bag
# closed); 2 bad arguments. No process of the run outlives it.
set -euo pipefail
export ALIGNMENT_COMMAND_START_NS="${ALIGNMENT_COMMAND_START_NS:-$(date +%s%N)}"   # start-up is timed from here
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.graph "$@"
