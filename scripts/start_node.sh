#!/usr/bin/env bash
# Start one node of the graph: scripts/start_node.sh NAME [--params-file F] [--ros-args ...]
# NAME: ship_motion_node | master_ins_node | slave_ins_node | ldv_node | alignment_filter_node
# Without --params-file the node runs the default scenario (config/params/graph.yaml).
# Scenario keys on top (-p aircraft.lever_arm_m:=[60.0,-15.0,20.0]) act as run_graph.sh's --set:
# the node resolves them with the same rules. An unknown or wrong-typed parameter stops the node
# at start-up (exit status 2, one line naming it). The nodes run on the stamps of their inputs and
# never read ROS time, so they are not started with use_sim_time (a /clock reader costs each
# node CPU for every ship sample).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh"
. "$ROOT/scripts/env.sh"
NAME="${1:?usage: start_node.sh NAME [--params-file F] [--ros-args ...]}"; shift
EXE="$ROOT/ros2_ws/install/$NAME/lib/$NAME/$NAME"
[ -x "$EXE" ] || { echo "start_node.sh: unknown node '$NAME'" >&2; exit 2; }
PARAMS="$ROOT/config/params/graph.yaml"
EXTRA=()
while [ $# -gt 0 ]; do
  case "$1" in
    --params-file) PARAMS="$2"; shift 2 ;;
    --ros-args) shift; EXTRA+=("$@"); break ;;
    *) EXTRA+=("$1"); shift ;;
  esac
done
exec "$EXE" --ros-args --params-file "$PARAMS" "${EXTRA[@]}"
