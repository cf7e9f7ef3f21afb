#!/usr/bin/env bash
# Run a benchmark from bench/ (installs the peers of requirements-bench.txt into the venv first):
#   scripts/bench.sh NAME [args]     e.g. scripts/bench.sh monte_carlo --runs 8
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" >&2
. "$ROOT/scripts/env.sh"
STAMP="$ROOT/.venv/.requirements-bench.sha"
want="$(sha256sum "$ROOT/requirements-bench.txt" | cut -d' ' -f1)"
if [ "$want" != "$(cat "$STAMP" 2>/dev/null || true)" ]; then
  echo "bench.sh: installing bench peers" >&2
  python -m pip install -q -r "$ROOT/requirements-bench.txt" && echo "$want" > "$STAMP"
fi
[ $# -ge 1 ] || { echo "usage: scripts/bench.sh NAME [args]; NAME one of: $(cd "$ROOT/bench" && ls *.py | sed 's/\.py$//' | tr '\n' ' ')" >&2; exit 2; }
name="$1"; shift
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
cd "$ROOT"
exec python "bench/$name.py" "$@"
