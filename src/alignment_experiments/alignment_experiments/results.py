"""Results files of an experiment, tidy and versioned:

- `runs.csv`: one row per run (cell values, seed, scored errors and 1-sigma in arcmin, NEES,
  settling times, mean NIS); byte-identical for the same experiment and seeds;
- `summary.csv`: one row per cell and axis (mean, std, RMS, 95th percentile, mean sigma,
  fraction inside 2 sigma, 1-dof NEES with its 95 % chi-square bounds, median settling time);
- `meta.json`: schema version, experiment definition, seeds, code version (no clock times);
- `series.npz`: per-run error and 1-sigma histories (float32 arcmin) for the plots;
- `timing.json`: wall-clock numbers (the only file that differs between identical runs).
"""
from __future__ import annotations

import csv
import dataclasses
import io
import json
import subprocess
from pathlib import Path

import numpy as np

from .experiment import AXES, Experiment
from .monte_carlo import RunOutcome
from .statistics import axis_stats, nees_bounds

SCHEMA_VERSION = 1


def _fmt(v) -> str:
    if isinstance(v, float):
        return repr(v) if np.isfinite(v) else ('nan' if np.isnan(v) else repr(v))
    return str(v)


def _csv(header: list[str], rows: list[list]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator='\n')
    w.writerow(header)
    for r in rows:
        w.writerow([_fmt(x) for x in r])
    return buf.getvalue()


def value_names(outcomes: list[RunOutcome]) -> list[str]:
    names: list[str] = []
    for o in outcomes:
        for k, _ in o.spec.values:
            if k not in names:
                names.append(k)
    return names


def runs_table(outcomes: list[RunOutcome], axes: tuple[str, ...] = AXES) -> tuple[list[str], list[list]]:
    vn = value_names(outcomes)
    header = (['run', 'cell'] + vn + ['seed', 'score_time_s']
              + [f'err_{a}_arcmin' for a in axes] + [f'sigma_{a}_arcmin' for a in axes]
              + ['nees'] + [f'settle_{a}_s' for a in axes] + ['nis_mean', 'updates'])
    rows = []
    for o in outcomes:
        vals = dict(o.spec.values)
        rows.append([o.spec.index, o.spec.cell] + [vals.get(k, '') for k in vn]
                    + [o.spec.seed, o.score_time_s] + [float(x) for x in o.err] + [float(x) for x in o.sigma]
                    + [o.nees] + [float(x) for x in o.settle_s] + [o.nis_mean, o.updates])
    return header, rows


def cells_of(outcomes: list[RunOutcome]) -> dict[str, list[RunOutcome]]:
    """Outcomes grouped by cell label, in first-appearance order."""
    out: dict[str, list[RunOutcome]] = {}
    for o in outcomes:
        out.setdefault(o.spec.cell, []).append(o)
    return out


def summary_table(outcomes: list[RunOutcome], axes: tuple[str, ...] = AXES) -> tuple[list[str], list[list]]:
    vn = value_names(outcomes)
    header = (['cell'] + vn + ['axis', 'n', 'mean_arcmin', 'std_arcmin', 'rms_arcmin', 'p95_arcmin',
                               'mean_sigma_arcmin', 'in_2sigma', 'nees', 'nees_lo', 'nees_hi',
                               'settle_median_s', 'settled_fraction'])
    rows = []
    for label, runs in cells_of(outcomes).items():
        vals = dict(runs[0].spec.values)
        err = np.array([o.err for o in runs])
        sig = np.array([o.sigma for o in runs])
        fin = np.all(np.isfinite(err), axis=1) & np.all(np.isfinite(sig), axis=1)   # diverged runs: see runs.csv
        if np.any(fin):
            err, sig = err[fin], sig[fin]
        settle = np.array([o.settle_s for o in runs])
        lo, hi = nees_bounds(1, len(err))
        for i, a in enumerate(axes):
            s = axis_stats(err[:, i], sig[:, i])
            ok = np.isfinite(settle[:, i])
            rows.append([label] + [vals.get(k, '') for k in vn]
                        + [a, s.n, s.mean, s.std, s.rms, s.p95, s.mean_sigma, s.in_2sigma, s.nees, lo, hi,
                           float(np.median(settle[ok, i])) if np.any(ok) else float('nan'), float(np.mean(ok))])
    return header, rows


def code_version(root: Path | None = None) -> str:
    """`git describe --always --dirty` of the project, or 'unknown'."""
    try:
        return subprocess.run(['git', 'describe', '--always', '--dirty'], cwd=root or Path(__file__).parent,
                              capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return 'unknown'


def write(out: Path, exp: Experiment, outcomes: list[RunOutcome], seeds: int, first_seed: int,
          wall_s: float, workers: int, version: str | None = None) -> None:
    """Write the results files; `version`: the code version the runs used (default: now)."""
    out.mkdir(parents=True, exist_ok=True)
    (out / 'runs.csv').write_text(_csv(*runs_table(outcomes, exp.axes)))
    (out / 'summary.csv').write_text(_csv(*summary_table(outcomes, exp.axes)))
    meta = {'schema_version': SCHEMA_VERSION, 'experiment': dataclasses.asdict(exp), 'seeds': seeds,
            'first_seed': first_seed, 'runs': len(outcomes),
            'code_version': version if version is not None else code_version()}
    (out / 'meta.json').write_text(json.dumps(meta, indent=1, default=str) + '\n')
    arrays: dict[str, np.ndarray] = {}
    for o in outcomes:
        arrays[f'run{o.spec.index}_t_s'] = o.t_s
        arrays[f'run{o.spec.index}_err_arcmin'] = o.err_t
        arrays[f'run{o.spec.index}_sigma_arcmin'] = o.sigma_t
    # allow_pickle: numpy's default, named so that mypy does not match **arrays against that bool flag
    np.savez_compressed(out / 'series.npz', allow_pickle=True, **arrays)
    (out / 'timing.json').write_text(json.dumps({
        'wall_s': wall_s, 'workers': workers, 'runs': len(outcomes),
        'runs_per_minute': 60.0 * len(outcomes) / wall_s if wall_s > 0 else None,
        'run_cpu_wall_s_mean': float(np.mean([o.wall_s for o in outcomes])) if outcomes else None}, indent=1) + '\n')


def read_runs(path: Path) -> list[dict[str, str]]:
    with open(path, newline='') as f:
        return list(csv.DictReader(f))
