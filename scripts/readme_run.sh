#!/usr/bin/env bash
# The README's example run, regenerated: scripts/run_graph.sh --scenario catapult, its misalignment
# plot copied to docs/img/run/, its result table and the command into README.md's run:example block.
#   scripts/readme_run.sh [--from RUN_DIR]     (--from: a finished run of that command)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
cd "$ROOT"
exec python -m alignment_ros.readme_run "$@"
