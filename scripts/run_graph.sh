#!/usr/bin/env bash
# Main job: run a scenario through the whole ROS 2 node graph, record everything to an MCAP
# bag, and print the alignment result.
#   scripts/run_graph.sh [--scenario NAME] [--out DIR] [--seed N] [--set KEY=VALUE ...]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.graph "$@"
