"""Run an air-data experiment (air_data_catalogue.py): every seed simulated once and estimated by
every cell, in parallel processes; scored per run (maximum, mean, spread and window RMS of the
Mach, alpha and beta errors; the worst error against the single-frame Cramer-Rao bound; the
normalised squared error at fixed instants for the NEES across runs); written as runs.csv,
summary.csv, meta.json, timing.json and report.md (the layout publish.py renders)."""
from __future__ import annotations

import dataclasses
import json
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from alignment_core import air_data_run
from alignment_core.air_data.fads_solver import cramer_rao_bound
from alignment_core.air_data.ports import PortModel
from alignment_core.config import scenario

from .air_data_catalogue import QUANTITIES, SHOWN, AirDataExperiment
from .results import _csv
from .statistics import nees_bounds

SCHEMA_VERSION = 1
CR_INDEX = {'alpha_rad': 0, 'beta_rad': 1, 'mach': 2}


def check_times(exp: AirDataExperiment, duration_s: float) -> list[float]:
    return [float(t) for t in np.arange(exp.check_every_s, duration_s + 1e-9, exp.check_every_s)]


def score(exp: AirDataExperiment, run: air_data_run.AirDataRun, cr_sigma: np.ndarray, duration_s: float) -> dict:
    """One run's numbers (see the module docstring); cr_sigma (K, 3): alpha, beta, Mach bounds."""
    out: dict[str, object] = {}
    keep = run.t >= exp.settle_s
    window = keep & (run.t >= exp.window[0]) & (run.t <= exp.window[1])
    labels = list(run.labels)
    claims = {c.quantity: c.bound for c in exp.claims}
    for q in QUANTITIES:
        i = labels.index(q)
        err = run.value[:, i] - run.truth[:, i]
        z2 = (err / run.sigma[:, i]) ** 2
        e = err[keep]
        k = int(np.argmax(np.abs(e)))
        cr = cr_sigma[keep, CR_INDEX[q]]
        over = np.abs(e) > claims.get(q, np.inf)
        out[f'{q}_max'] = float(np.abs(e[k]))
        out[f'{q}_t_of_max'] = float(run.t[keep][k])
        out[f'{q}_cr_at_max'] = float(cr[k])
        out[f'{q}_worst_over_cr'] = float(np.max(np.abs(e[over]) / cr[over])) if np.any(over) else 0.0
        out[f'{q}_mean'] = float(np.mean(e))
        out[f'{q}_std'] = float(np.std(e))
        out[f'{q}_rms_window'] = float(np.sqrt(np.mean(err[window] ** 2))) if np.any(window) else float('nan')
        for t in check_times(exp, duration_s):
            j = int(np.argmin(np.abs(run.t - t)))
            out[f'z2_{q}_{t:g}'] = float(z2[j])
    if exp.wind_after_s is not None:
        late = run.t >= exp.wind_after_s
        if not np.any(late):                               # a quick run that ends before: its last 60 s
            late = run.t >= run.t[-1] - 60.0
        nees = np.zeros(int(np.sum(late)))
        for axis in ('east', 'north', 'up'):
            i = labels.index(f'wind_{axis}_mps')
            e = run.value[late, i] - run.truth[late, i]
            out[f'wind_{axis}_rms'] = float(np.sqrt(np.mean(e**2)))
            out[f'wind_{axis}_sigma'] = float(np.sqrt(np.mean(run.sigma[late, i] ** 2)))
            nees += (e / run.sigma[late, i]) ** 2
        out['wind_nees'] = float(np.mean(nees))
    if exp.fault_at_s is not None:
        after = [t for t, _ in run.detections if t >= exp.fault_at_s - 1e-9]
        out['detect_after_fault_s'] = float(after[0] - exp.fault_at_s) if after else float('nan')
        out['false_exclusions'] = sum(1 for t, _ in run.detections if t < exp.fault_at_s - 1e-9)
    out['updates'] = int(run.counts.get('updates', 0))
    out['gated'] = int(run.counts.get('gated', 0))
    out['excluded'] = ' '.join(str(p) for p in run.excluded_ports)
    out['unhealthy'] = int(np.sum(~run.healthy))
    return out


def run_seed(exp: AirDataExperiment, seed: int) -> list[dict]:
    """Simulate one seed (once per distinct simulation: cells that only change the estimator share
    it) and estimate it with every cell."""
    sims: dict[tuple, air_data_run.AirDataInputs] = {}
    rows = []
    for cell in exp.cells:
        wall = time.perf_counter()
        csc = scenario.load(exp.scenario, dict(exp.base + cell.overrides), seed=seed)
        key = tuple((k, v) for k, v in cell.overrides if not k.startswith('air_data_filter.'))
        if key not in sims:
            sims[key] = air_data_run.simulate(csc)
        inp = sims[key]
        sc = csc
        run = air_data_run.estimate(csc, inp, form=cell.form, algorithm=cell.algorithm)
        labels = list(run.labels)
        a, b, m, p = (run.truth[:, labels.index(n)] for n in ('alpha_rad', 'beta_rad', 'mach', 'static_pressure_pa'))
        model = PortModel(sc.fads.geometry, sc.fads.epsilon)
        cov = np.eye(model.geometry.count) * sc.fads.sigma_pa**2
        cr = np.sqrt(np.diagonal(cramer_rao_bound(model, a, b, m, p, cov), axis1=-2, axis2=-1))
        row = {'cell': cell.label, 'form': cell.form, 'algorithm': cell.algorithm, 'seed': seed}
        row.update(score(exp, run, cr[:, :3], sc.duration_s))
        row['wall_s'] = time.perf_counter() - wall
        rows.append(row)
    return rows


def run_all(exp: AirDataExperiment, seeds: int, first_seed: int = 1, workers: int = 2) -> list[dict]:
    """Rows in (seed, cell) order whatever the worker count."""
    todo = list(range(first_seed, first_seed + seeds))
    if workers <= 1:
        per_seed = [run_seed(exp, s) for s in todo]
    else:
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context('fork')) as ex:
            per_seed = list(ex.map(run_seed, [exp] * len(todo), todo))
    return [r for rows in per_seed for r in rows]


def write(out: Path, exp: AirDataExperiment, rows: list[dict], seeds: int, first_seed: int, wall_s: float,
          workers: int, version: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    header = [k for k in rows[0] if k != 'wall_s']
    (out / 'runs.csv').write_text(_csv(['run'] + header, [[i] + [r[k] for k in header] for i, r in enumerate(rows)]))
    summary = summarise(exp, rows)
    (out / 'summary.csv').write_text(_csv(list(summary[0]), [list(s.values()) for s in summary]))
    meta = {'schema_version': SCHEMA_VERSION, 'experiment': dataclasses.asdict(exp), 'seeds': seeds,
            'first_seed': first_seed, 'code_version': version}
    (out / 'meta.json').write_text(json.dumps(meta, indent=1, default=str))
    (out / 'timing.json').write_text(json.dumps({'wall_s': wall_s, 'workers': workers,
                                                 'run_wall_s': [r['wall_s'] for r in rows]}, indent=1))


def summarise(exp: AirDataExperiment, rows: list[dict]) -> list[dict]:
    """Per cell and quantity: worst, mean, std, window RMS over the runs; NEES across runs at the
    check instants (mean, and the share of instants inside the 95 % bounds)."""
    out = []
    for cell in exp.cells:
        rs = [r for r in rows if r['cell'] == cell.label]
        n = len(rs)
        lo, hi = nees_bounds(1, n)
        for q in QUANTITIES:
            z2 = np.array([[r[k] for k in r if k.startswith(f'z2_{q}_')] for r in rs])
            anees = np.mean(z2, axis=0)
            out.append({'cell': cell.label, 'quantity': q, 'n': n,
                        'max': max(r[f'{q}_max'] for r in rs),
                        'mean': float(np.mean([r[f'{q}_mean'] for r in rs])),
                        'std': float(np.sqrt(np.mean([r[f'{q}_std'] ** 2 for r in rs]))),
                        'rms_window': float(np.sqrt(np.mean([r[f'{q}_rms_window'] ** 2 for r in rs]))),
                        'worst_over_cr': max(r[f'{q}_worst_over_cr'] for r in rs),
                        'anees_mean': float(np.mean(anees)), 'anees_lo': lo, 'anees_hi': hi,
                        'anees_inside': float(np.mean((anees >= lo) & (anees <= hi))),
                        'gated_mean': float(np.mean([r['gated'] for r in rs]))})
    return out


def wind_and_fault_table(exp: AirDataExperiment, rows: list[dict]) -> str:
    """Per cell: wind RMS with its mean 1-sigma and the mean 3-dof NEES (95 % bounds), the
    detection delay of a failed port and false exclusions."""
    head = ['cell', 'wind RMS E/N/U m/s', 'mean 1σ E/N/U m/s', 'wind NEES (95 % bounds)',
            'detected after (s): median, max', 'runs detected', 'false exclusions']
    lines = ['| ' + ' | '.join(head) + ' |', '|' + '---|' * len(head)]
    for cell in exp.cells:
        rs = [r for r in rows if r['cell'] == cell.label]
        rms = [float(np.sqrt(np.mean([r[f'wind_{a}_rms'] ** 2 for r in rs]))) for a in ('east', 'north', 'up')]
        sig = [float(np.sqrt(np.mean([r[f'wind_{a}_sigma'] ** 2 for r in rs]))) for a in ('east', 'north', 'up')]
        lo, hi = nees_bounds(3, len(rs))
        nees = float(np.mean([r['wind_nees'] for r in rs]))
        det = np.array([r.get('detect_after_fault_s', np.nan) for r in rs], dtype=float)
        faulty = any(k == 'fads.faults' for k, _ in cell.overrides)
        found = det[np.isfinite(det)]
        lines.append('| ' + ' | '.join([
            cell.label, '/'.join(f'{x:.3f}' for x in rms), '/'.join(f'{x:.3f}' for x in sig),
            f'{nees:.2f} [{lo:.2f}, {hi:.2f}]',
            (f'{np.median(found):.2f}, {np.max(found):.2f}' if len(found) else '-') if faulty else '-',
            f'{len(found)} of {len(rs)}' if faulty else '-',
            str(sum(int(r.get('false_exclusions', 0)) for r in rs))]) + ' |')
    return '\n'.join(lines)


def _f(v: float, q: str, digits: int = 3) -> str:
    return f'{v * SHOWN[q][1]:.{digits}g}'


def report(out: Path, exp: AirDataExperiment, rows: list[dict], seeds: int) -> Path:
    summary = summarise(exp, rows)
    by = {(s['cell'], s['quantity']): s for s in summary}
    head = ['cell'] + [f'{SHOWN[q][0]} {w}{SHOWN[q][2]}' for q in QUANTITIES for w in ('RMS cruise', 'max')] + \
        [f'NEES {SHOWN[q][0]} (95 % bounds)' for q in QUANTITIES] + ['gated frames']
    lines = ['| ' + ' | '.join(head) + ' |', '|' + '---|' * len(head)]
    for cell in exp.cells:
        s = [by[(cell.label, q)] for q in QUANTITIES]
        cols = [cell.label] + [c for x, q in zip(s, QUANTITIES) for c in (_f(x['rms_window'], q), _f(x['max'], q))]
        cols += [f"{x['anees_mean']:.2f} [{x['anees_lo']:.2f}, {x['anees_hi']:.2f}], "
                 f"{100 * x['anees_inside']:.0f} % inside" for x in s]
        cols.append(f"{s[0]['gated_mean']:.1f}")
        lines.append('| ' + ' | '.join(cols) + ' |')
    md = [f'# {exp.title}', '', exp.description, '', f'{seeds} seeds per cell.', '', '## Results per cell', '',
          *lines, '']
    if exp.wind_after_s is not None:
        md += ['## Wind and port faults', '', wind_and_fault_table(exp, rows), '']
    if exp.claims:
        md += ['## Beside the paper', '', _beside(exp, by), '']
    path = out / 'report.md'
    path.write_text('\n'.join(md))
    return path


def _beside(exp: AirDataExperiment, by: dict) -> str:
    rows = ['| quantity | paper: bound on the error | ours, worst of all runs (tight ckf) | ratio | worst / '
            'single-frame CR where above the bound | paper: CKF cut of the max vs EKF | ours: paper form | '
            'ours: tight form |',
            '|---|---|---|---|---|---|---|---|']
    for c in exp.claims:
        q = c.quantity
        tight = by.get(('tight ckf', q))
        if tight is None:
            continue

        def cut(form: str, q: str = q) -> str:
            e, k = by.get((f'{form} ekf', q)), by.get((f'{form} ckf', q))
            return f"{100 * (1 - k['max'] / e['max']):.1f} %" if e and k and e['max'] > 0 else '-'
        rows.append(f"| {SHOWN[q][0]} | {_f(c.bound, q)}{SHOWN[q][2]} | {_f(tight['max'], q)}{SHOWN[q][2]} | "
                    f"{tight['max'] / c.bound:.2f} | {tight['worst_over_cr']:.2f} | "
                    f"{'-' if c.ckf_cut_of_max is None else f'{100 * c.ckf_cut_of_max:.0f} %'} | {cut('paper')} | "
                    f"{cut('tight')} |")
    return '\n'.join(rows)
