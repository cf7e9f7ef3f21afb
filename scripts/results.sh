#!/usr/bin/env bash
# Re-run the catalogue's experiments at their documented seeds and regenerate docs/results.md and
# the README's result tables from their output files:
#   scripts/results.sh [NAME ...] [--workers W] [--render-only]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
cd "$ROOT"
exec python -m alignment_experiments.publish "$@"
