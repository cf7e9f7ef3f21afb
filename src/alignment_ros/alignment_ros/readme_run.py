"""``scripts/readme_run.sh [--from RUN_DIR]``: the README's example run, regenerated. Runs
``scripts/run_graph.sh --scenario catapult`` (or takes a finished run directory), copies its
misalignment plot to docs/img/run/ and rewrites the README block between
``<!-- run:example -->`` and ``<!-- /run:example -->`` with the run's result table (from its
summary.json), the plot, and the commit, date and command that made them. Never by hand."""
from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from .launch import root
from .run_report import result_table

COMMAND = ['scripts/run_graph.sh', '--scenario', 'catapult']
IMAGE = Path('docs/img/run/catapult_misalignment.png')
BLOCK_RE = re.compile(r'(<!-- run:example -->\n)(.*?)(<!-- /run:example -->)', re.S)


def _version(top: Path) -> str:
    try:
        return subprocess.run(['git', 'describe', '--always', '--dirty'], cwd=top, capture_output=True,
                              text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return 'unknown'


def block(s: dict, image: Path, version: str, date: str) -> str:
    lines = [*result_table(s), '', f'![The misalignment estimate of this run]({image.as_posix()})', '',
             f"(made by commit `{version}`, {date}, `{' '.join(COMMAND)}`: simulated {s['sim_time_s']:.0f} s; "
             f"its `report.md` and the other plots are in the run directory; regenerate with "
             f"`scripts/readme_run.sh`.)"]
    return '\n'.join(lines) + '\n'


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog='readme_run.sh', description=__doc__)
    ap.add_argument('--from', dest='run', type=Path, default=None,
                    help='a finished run of the same command (default: run it now)')
    a = ap.parse_args(argv)
    top = root()
    version = _version(top)
    run = a.run
    if run is None:
        run = top / 'runs' / time.strftime('readme-catapult-%Y%m%d-%H%M%S')
        p = subprocess.run([str(top / COMMAND[0]), *COMMAND[1:], '--out', str(run)], cwd=top)
        if p.returncode != 0:
            print(f'readme_run: the run failed ({p.returncode}); README unchanged', file=sys.stderr)
            return 1
    s = json.loads((run / 'summary.json').read_text())
    if not s.get('complete') or s.get('scenario') != 'catapult':
        print(f'readme_run: {run} is not a complete catapult run; README unchanged', file=sys.stderr)
        return 1
    (top / IMAGE).parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(run / 'plots' / 'misalignment.png', top / IMAGE)
    readme = top / 'README.md'
    text = readme.read_text()
    if not BLOCK_RE.search(text):
        print('readme_run: README.md has no <!-- run:example --> block', file=sys.stderr)
        return 1
    new = block(s, IMAGE, version, time.strftime('%Y-%m-%d'))
    readme.write_text(BLOCK_RE.sub(lambda m: m.group(1) + new + m.group(3), text))
    print(f'README.md: example run from {run}; {IMAGE}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
