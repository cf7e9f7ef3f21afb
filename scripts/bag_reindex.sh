#!/usr/bin/env bash
# Rebuild a rosbag2 MCAP bag's metadata.yaml and MCAP summary/index from what was written, like
# `ros2 bag reindex` (a recorder killed before it closed the bag, a file cut short mid-chunk:
# every complete message is kept). Only on a bag no recorder is writing any more.
#   scripts/bag_reindex.sh BAG
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.bag_reindex "$@"
