"""`scripts/results.sh [NAME ...]`: run the catalogue's experiments at their documented seeds and
publish their numbers: `docs/results.md` (every table and plot, stamped with the commit, the date,
the command and the core count) and the README's result blocks, both taken from the experiments'
own output files, never typed by hand.

Freshness: `docs/results.md` records, per experiment, the SHA-256 of its quick version's
`runs.csv` (the experiments are deterministic). The test suite re-runs the quick versions and
calls `check_fresh`, which fails when the code no longer gives the published numbers. The
digest (`sha256r6=`) is taken over the file with every number rounded to 6 significant digits:
the same code on another CPU (other SIMD kernels, another BLAS summation order) moves the last
bits of a float, not its sixth digit. An older exact digest (`sha256=`) is still checked
exactly until its experiment is published again.
"""
from __future__ import annotations

import argparse
import csv
import datetime
import hashlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from .air_data_catalogue import AIR_DATA_EXPERIMENTS, AirDataExperiment
from .catalogue import CATALOGUE
from .experiment import Experiment

ROOT = Path(os.environ.get('ALIGN_ROOT') or Path(__file__).resolve().parents[3])
RESULTS_MD = ROOT / 'docs' / 'results.md'
README = ROOT / 'README.md'
IMG_DIR = ROOT / 'docs' / 'img' / 'results'
OUT_DIR = ROOT / 'runs' / 'results'
PLOTS = ('rms_by_cell.png', 'nees.png')          # + rms_vs_<sweep>.png; error_vs_time stays in the run dir
DIGEST_RE = re.compile(r'<!-- quick-digest (\S+) (sha256|sha256r6)=([0-9a-f]{64}) -->')
ROUND_DIGITS = 6
README_BLOCK_RE = re.compile(r'(<!-- results:(\S+) -->\n)(.*?)(<!-- /results:\2 -->)', re.S)
STALE = 'results are stale: run scripts/results.sh'


class StaleResultsError(AssertionError):
    """The code no longer gives the numbers docs/results.md publishes."""


def _rounded(cell: str) -> str:
    try:
        v = float(cell)
    except ValueError:
        return cell
    return cell if cell.lstrip('-').isdigit() else f'{v:.{ROUND_DIGITS}g}'


def digest(runs_csv: Path, kind: str = 'sha256r6') -> str:
    """SHA-256 of runs.csv: exact ('sha256') or with every number rounded ('sha256r6')."""
    if kind == 'sha256':
        return hashlib.sha256(runs_csv.read_bytes()).hexdigest()
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator='\n')
    for row in csv.reader(io.StringIO(runs_csv.read_text())):
        w.writerow([_rounded(c) for c in row])
    return hashlib.sha256(buf.getvalue().encode()).hexdigest()


def recorded_digests(text: str) -> dict[str, tuple[str, str]]:
    """name -> (kind, hex digest)."""
    return {name: (kind, hexd) for name, kind, hexd in DIGEST_RE.findall(text)}


def check_fresh(name: str, runs_csv: Path, results_md: Path = RESULTS_MD) -> None:
    """Raise StaleResultsError unless `runs_csv` (a quick run of `name`) is what results_md published."""
    have = recorded_digests(results_md.read_text()) if results_md.exists() else {}
    if name not in have:
        raise StaleResultsError(f'{STALE} ({name}: {results_md.name} records no quick digest)')
    kind, want = have[name]
    got = digest(runs_csv, kind)
    if want != got:
        raise StaleResultsError(f'{STALE} ({name}: {results_md.name} records {want[:12]}, '
                                f'the code gives {got[:12]})')


def _sections(report_md: str) -> dict[str, str]:
    """'## Heading' -> its body, from an experiment's report.md."""
    out: dict[str, str] = {}
    for part in re.split(r'^## ', report_md, flags=re.M)[1:]:
        head, _, body = part.partition('\n')
        out[head.strip()] = body.strip('\n')
    return out


def _first_table(text: str) -> list[list[str]]:
    rows = [ln for ln in text.splitlines() if ln.startswith('|')]
    return [[c.strip() for c in ln.strip('|').split('|')] for ln in rows]


def _table(rows: list[list[str]]) -> str:
    return '\n'.join('| ' + ' | '.join(r) + ' |' for r in rows)


def compact_table(report_md: str) -> str:
    """The per-cell results table with the columns a README reader needs (cell values, RMS, mean 1σ,
    NEES with its bounds)."""
    rows = _first_table(_sections(report_md)['Results per cell'])
    head = rows[0]
    keep = [i for i, h in enumerate(head) if not h.startswith(('p95', 'in 2σ', 'mean NIS', 'settle'))]
    return _table([[r[i] for i in keep] for r in rows])


def experiments() -> dict[str, Experiment | AirDataExperiment]:
    """Every published experiment, by name: the alignment catalogue's, then the air-data ones."""
    return {**CATALOGUE.experiments, **AIR_DATA_EXPERIMENTS}


def stamp(exp: Experiment | AirDataExperiment, out: Path) -> str:
    """Commit, date, command and core count of the run in `out`, from its own files (meta.json holds
    the commit and seeds the run used, timing.json its workers; the date is that of runs.csv)."""
    meta = json.loads((out / 'meta.json').read_text())
    timing = json.loads((out / 'timing.json').read_text())
    day = datetime.datetime.fromtimestamp((out / 'runs.csv').stat().st_mtime, datetime.UTC).strftime('%Y-%m-%d')
    return (f"commit `{meta['code_version']}`, {day}, `scripts/experiment.sh {exp.name} --seeds {meta['seeds']} "
            f"--workers {timing['workers']}`, {os.cpu_count()} cores")


def section(exp: Experiment | AirDataExperiment, out: Path, quick_out: Path, stamp_line: str) -> str:
    """This experiment's part of docs/results.md (its plots copied to docs/img/results/)."""
    rep = _sections((out / 'report.md').read_text())
    md = [f'## {exp.title}', '', f'<a id="{exp.name}"></a>', exp.description, '', f'Made by {stamp_line}.', '',
          rep['Results per cell']]
    for extra in ('Wind and port faults', 'Beside the paper'):
        if extra in rep:
            md += ['', f'### {extra}', '', rep[extra]]
    if exp.notes:
        md += ['', '### Reading', '', exp.notes]
    IMG_DIR.mkdir(parents=True, exist_ok=True)
    shown = [p for p in PLOTS + (f'rms_vs_{exp.sweep}.png',) if (out / p).exists()]
    for p in shown:
        shutil.copyfile(out / p, IMG_DIR / f'{exp.name}-{p}')
    md += [''] + [f'![{exp.name}: {p[:-4]}](img/results/{exp.name}-{p})' for p in shown]
    md += ['', f'<!-- quick-digest {exp.name} sha256r6={digest(quick_out / "runs.csv")} -->', '']
    return '\n'.join(md)


def readme_block(exp: Experiment | AirDataExperiment, out: Path, stamp_line: str) -> str:
    md = [compact_table((out / 'report.md').read_text()), '',
          f'({exp.name}; made by {stamp_line}; all columns, the paper comparison and plots in '
          f'[docs/results.md](docs/results.md#{exp.name}).)']
    if exp.notes:
        md += ['', exp.notes]
    return '\n'.join(md) + '\n'


def update_readme(text: str, blocks: dict[str, str]) -> str:
    """Replace each `<!-- results:NAME -->` ... `<!-- /results:NAME -->` block whose NAME is in blocks."""
    return README_BLOCK_RE.sub(lambda m: m.group(1) + blocks.get(m.group(2), m.group(3)) + m.group(4), text)


def published_sections(text: str) -> dict[str, str]:
    """Each experiment's section of an existing docs/results.md, by name (its `<a id>`), verbatim."""
    out: dict[str, str] = {}
    for part in re.split(r'^(?=## )', text, flags=re.M):
        m = re.search(r'<a id="([^"]+)"></a>', part)
        if part.startswith('## ') and m:
            out[m.group(1)] = part.rstrip('\n') + '\n'
    return out


def _run(args: list[str]) -> None:
    cmd = [sys.executable, '-m', 'alignment_experiments', *args]
    print('+', ' '.join(cmd[2:]), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog='results.sh', description=__doc__.split('\n\n')[0])
    ap.add_argument('names', nargs='*', help='experiments to re-run (default: all); the others are rendered '
                                             'from their last outputs in runs/results/, or, without any, kept '
                                             'as docs/results.md has them')
    ap.add_argument('--workers', type=int, default=2)
    ap.add_argument('--render-only', action='store_true', help='do not run; render from runs/results/')
    ap.add_argument('--redigest', nargs='+', default=[], metavar='NAME',
                    help='for experiments whose published section is kept: re-run only their quick version '
                         'and record its rounded digest (sha256r6) in place of an exact one; their tables stand')
    a = ap.parse_args(argv)
    known = experiments()
    names = a.names or ([] if a.redigest else list(known))
    for n in names:
        if n not in known:
            ap.error(f"unknown experiment {n!r} (known: {', '.join(known)})")
    if not a.render_only:
        for n in names:
            _run([n, '--workers', str(a.workers), '--out', str(OUT_DIR / n)])
            _run([n, '--quick', '--workers', str(a.workers), '--out', str(OUT_DIR / f'{n}_quick')])
    have = {n for n in known
            if all((OUT_DIR / d / f).exists() for d in (n, f'{n}_quick') for f in ('report.md', 'meta.json'))}
    kept = published_sections(RESULTS_MD.read_text()) if RESULTS_MD.exists() else {}
    for n in a.redigest:
        if n not in kept:
            ap.error(f'--redigest {n}: docs/results.md has no section for it')
        _run([n, '--quick', '--workers', str(a.workers), '--out', str(OUT_DIR / f'{n}_quick')])
        kept[n] = DIGEST_RE.sub(f'<!-- quick-digest {n} sha256r6={digest(OUT_DIR / f"{n}_quick" / "runs.csv")} -->',
                                kept[n])
    missing = [n for n in known if n not in have and n not in kept]
    if missing:
        ap.error(f"no outputs for {', '.join(missing)}: run scripts/results.sh {' '.join(missing)}")
    parts = ['# Results', '',
             'Every table here is generated by `scripts/results.sh` from the experiments\' output files '
             '(`runs/results/NAME/report.md`, `runs.csv`, plots) and stamped with the commit, date, command and core '
             'count that made it. The test suite re-runs each experiment\'s quick version and fails when its '
             '`runs.csv` no longer matches the digest recorded below it: a change that moves a number cannot land '
             'with the old number here. Errors in arcmin; ROS FLU aircraft axes (roll = x, pitch = y, yaw = z) '
             'unless the table says E/N/U. The papers are identified in [references.md](references.md).', '']
    blocks = {}
    for n, exp in known.items():
        if n not in have:               # not re-run here: its published section stands (its own stamp,
            parts.append(kept[n])       # its digest still checked by the tests)
            continue
        made_by = stamp(exp, OUT_DIR / n)
        parts.append(section(exp, OUT_DIR / n, OUT_DIR / f'{n}_quick', made_by))
        blocks[n] = readme_block(exp, OUT_DIR / n, made_by)
    RESULTS_MD.write_text('\n'.join(parts))
    README.write_text(update_readme(README.read_text(), blocks))
    print(f'wrote {RESULTS_MD.relative_to(ROOT)} and the README blocks of {len(blocks)} experiments')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
