#!/usr/bin/env bash
# Replay a recorded bag's sensor topics into a fresh alignment filter and record its outputs.
#   scripts/replay.sh BAG [--out DIR] [--params-file F] [--set KEY=VALUE ...] [--domain-id N]
# BAG: a run of run_graph.sh or a bag of scripts/import_log.sh (docs/own-data.md).
# A damaged BAG is repaired first (scripts/bag_reindex.sh). Exit status as run_graph.sh's.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
. "$ROOT/scripts/env.sh"
exec python -m alignment_ros.replay "$@"
