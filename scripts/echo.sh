#!/usr/bin/env bash
# Print a topic's messages like `ros2 topic echo`: scripts/echo.sh TOPIC [--once] [--csv] [--timeout S]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec "$ROOT/ros2_ws/install/alignment_ros/lib/alignment_ros/echo" "$@"
