#!/usr/bin/env bash
# Print a topic's messages like `ros2 topic echo` (same options, defaults and exit status):
#   scripts/echo.sh TOPIC [TYPE] [--once] [--csv] [--field a.b] [--timeout S] ...
#   (scripts/echo.sh --help lists them)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec "$ROOT/ros2_ws/install/alignment_ros/lib/alignment_ros/echo" "$@"
