#!/usr/bin/env bash
# Import a recorded log into a bag that scripts/replay.sh and scripts/play.sh take:
#   scripts/import_log.sh --imu IMU --master MASTER [--ldv LDV] [--doppler DOPPLER]
#                         [--map MAP.yaml] [--origin LAT_DEG,LON_DEG] --out BAGDIR
# Layouts (canonical CSV, or a map for others): docs/own-data.md.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.importer "$@"
