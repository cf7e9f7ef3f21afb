#!/usr/bin/env bash
# Run the whole test suite (sets the workspace up first when needed). Extra args go to pytest.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
. "$ROOT/scripts/env.sh"
cd "$ROOT"
ruff check src tests bench experiments
mypy                     # every package (mypy.ini)
exec python -m pytest -q tests "$@"
