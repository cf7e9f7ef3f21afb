#!/usr/bin/env bash
# Run a catalogued Monte Carlo experiment through the batch pipeline and write its report:
#   scripts/experiment.sh NAME [--seeds N] [--workers W] [--quick] [--out DIR] [--scheduler ADDR]
#   scripts/experiment.sh --list
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
# one BLAS thread per worker process: the filter's matrices are small and workers run in parallel
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
cd "$ROOT"
exec python -m alignment_experiments "$@"
