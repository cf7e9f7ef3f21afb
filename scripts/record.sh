#!/usr/bin/env bash
# Record topics to a rosbag2 MCAP bag like `ros2 bag record` (same options and defaults;
# Ctrl-C ends the recording and finalises the bag):
#   scripts/record.sh -a | TOPIC... | -e REGEX  [-o DIR] [-x REGEX] [--exclude-topics T...]
#                     [-d S] [-b BYTES] [--compression-mode file|message --compression-format zstd]
#   (scripts/record.sh --help lists them)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.recorder "$@"
