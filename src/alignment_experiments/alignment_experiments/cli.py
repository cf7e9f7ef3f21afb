"""`scripts/experiment.sh NAME [options]`: run a catalogued Monte Carlo experiment and write
its results files and report into runs/experiments/NAME (or --out)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from . import air_data_runs, monte_carlo, report, results
from .air_data_catalogue import AIR_DATA_EXPERIMENTS, AirDataExperiment
from .catalogue import CATALOGUE
from .experiment import Experiment


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog='experiment.sh', description=__doc__)
    ap.add_argument('name', nargs='?', help='experiment name (see --list)')
    ap.add_argument('--list', action='store_true', help='list the experiments and exit')
    ap.add_argument('--seeds', type=int, default=None, help='seeds per cell (default: the experiment\'s)')
    ap.add_argument('--first-seed', type=int, default=1)
    ap.add_argument('--workers', type=int, default=2, help='local worker processes (default 2)')
    ap.add_argument('--scheduler', default=None,
                    help="Dask scheduler address, or 'local' for a local Dask cluster (needs dask[distributed])")
    ap.add_argument('--quick', action='store_true', help='tiny version: 2 seeds, few cells, short runs')
    ap.add_argument('--out', type=Path, default=None, help='output directory (default runs/experiments/NAME)')
    a = ap.parse_args(argv)
    if a.list or not a.name:
        listed: list[Experiment | AirDataExperiment] = [*CATALOGUE.experiments.values(),
                                                        *AIR_DATA_EXPERIMENTS.values()]
        for e in listed:
            print(f'{e.name:18s} {e.title}')
        return 0
    if a.seeds is not None and a.seeds < 1:
        ap.error('--seeds must be >= 1')
    if a.name in AIR_DATA_EXPERIMENTS:
        return _air_data(a)
    try:
        exp = CATALOGUE.get(a.name)
    except KeyError as e:
        ap.error(str(e.args[0]))
    if a.quick:
        exp = exp.quick(seeds=a.seeds or 2)
    seeds = a.seeds or exp.seeds
    out = a.out or Path('runs') / 'experiments' / (exp.name + ('_quick' if a.quick else ''))
    specs = exp.specs(seeds, a.first_seed)
    print(f'{exp.name}: {len(exp.cells)} cells x {seeds} seeds = {len(specs)} runs, '
          f'{a.workers if not a.scheduler else "dask"} workers -> {out}')
    version = results.code_version()          # the code the runs use, taken before they start
    wall = time.perf_counter()
    outcomes = monte_carlo.run_many(specs, workers=a.workers, scheduler=a.scheduler)
    wall = time.perf_counter() - wall
    results.write(out, exp, outcomes, seeds, a.first_seed, wall, a.workers, version)
    path = report.write_report(out, exp, outcomes, seeds, a.first_seed)
    print(f'{len(specs)} runs in {wall:.1f} s ({60 * len(specs) / wall:.1f} runs/min); report: {path}')
    return 0


def _air_data(a: argparse.Namespace) -> int:
    """An air-data experiment (air_data_runs.py): same options, its own files."""
    exp = AIR_DATA_EXPERIMENTS[a.name]
    if a.quick:
        exp = exp.quick(seeds=a.seeds or 2)
    seeds = a.seeds or exp.seeds
    out = a.out or Path('runs') / 'experiments' / (exp.name + ('_quick' if a.quick else ''))
    print(f'{exp.name}: {len(exp.cells)} cells x {seeds} seeds, {a.workers} workers -> {out}')
    version = results.code_version()
    wall = time.perf_counter()
    rows = air_data_runs.run_all(exp, seeds, a.first_seed, a.workers)
    wall = time.perf_counter() - wall
    air_data_runs.write(out, exp, rows, seeds, a.first_seed, wall, a.workers, version)
    path = air_data_runs.report(out, exp, rows, seeds)
    print(f'{len(rows)} runs in {wall:.1f} s; report: {path}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
