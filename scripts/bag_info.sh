#!/usr/bin/env bash
# Print what `ros2 bag info` prints about a rosbag2 MCAP bag (directory or .mcap file):
#   scripts/bag_info.sh BAG [-t]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.bag_info "$@"
