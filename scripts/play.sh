#!/usr/bin/env bash
# Play a bag like `ros2 bag play` (same options and defaults: --rate 1.0, --loop, --clock [HZ],
# --start-offset, --delay, --playback-duration, --playback-until-sec/-nsec, --topics,
# --exclude-topics, -e/-x regexes, --remap old:=new, --qos-profile-overrides-path ...):
#   scripts/play.sh BAG [options]        (scripts/play.sh --help lists them)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
[ -f "$ROOT/scripts/env.sh" ] && [ -d "$ROOT/ros2_ws/install" ] || "$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
exec "$ROOT/ros2_ws/install/alignment_ros/lib/alignment_ros/player" "$@"
