#!/usr/bin/env bash
# Replay a recorded bag's sensor topics into a fresh alignment filter and record its outputs.
#   scripts/replay.sh BAG [--out DIR] [--params-file F] [--domain-id N]
# A damaged BAG is repaired first (scripts/bag_reindex.sh). Exit status as run_graph.sh's.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.replay "$@"
