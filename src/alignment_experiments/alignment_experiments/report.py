"""Experiment report: `report.md` (conditions, results per cell, our numbers beside the
paper's with the ratio) and PNG plots (error vs time with 3-sigma envelopes, RMS vs the swept
variable, per-cell RMS bars, average NEES vs time with its chi-square bounds)."""
from __future__ import annotations

from pathlib import Path
from typing import SupportsFloat

import numpy as np

from .experiment import Experiment
from .monte_carlo import RunOutcome
from .results import cells_of, code_version, value_names
from .statistics import axis_stats, nees_bounds

MAX_SERIES_CELLS = 6


def _f(x: float, nd: int = 3) -> str:
    return '–' if x is None or not np.isfinite(x) else f'{x:.{nd}f}'


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '|'.join('---' for _ in header) + '|']
    lines += ['| ' + ' | '.join(r) + ' |' for r in rows]
    return '\n'.join(lines)


def _matches(values: dict, match: tuple) -> bool:
    return all(values.get(k) == v for k, v in match)


def _plots(out: Path, exp: Experiment, cells: dict[str, list[RunOutcome]]) -> list[str]:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    files = []

    # error vs time, one row per cell (first cells), one column per axis
    show = list(cells.items())[:MAX_SERIES_CELLS]
    fig, axs = plt.subplots(len(show), 3, figsize=(13, 2.4 * len(show) + 0.6), squeeze=False, sharex='row')
    for r, (label, runs) in enumerate(show):
        for i, a in enumerate(exp.axes):
            ax = axs[r, i]
            for o in runs:
                ax.plot(o.t_s, o.err_t[:, i], lw=0.6, alpha=0.6)
            sig = np.mean([o.sigma_t[:, i] for o in runs], axis=0)
            ax.plot(runs[0].t_s, 3 * sig, 'k--', lw=1.0, label='±3σ (mean)')
            ax.plot(runs[0].t_s, -3 * sig, 'k--', lw=1.0)
            ax.axvline(runs[0].score_time_s, color='grey', lw=0.8, ls=':')
            cand = [3 * float(np.nanmax(sig[len(sig) // 3:])) if np.any(np.isfinite(sig)) else 0.0]
            cand += [1.5 * abs(float(o.err[i])) for o in runs if np.isfinite(o.err[i])]
            lim = max(max(cand), 1e-3)
            ax.set_ylim(-lim, lim)
            ax.grid(alpha=0.3)
            if r == 0:
                ax.set_title(f'{a} error (arcmin)')
            if i == 0:
                ax.set_ylabel(label, fontsize=7)
            if r == len(show) - 1:
                ax.set_xlabel('time since start (s)')
    axs[0, 0].legend(fontsize=7, loc='upper right')
    fig.suptitle(f'{exp.name}: error vs time, {len(show[0][1])} runs per cell', fontsize=10)
    fig.tight_layout()
    fig.savefig(out / 'error_vs_time.png', dpi=90)
    plt.close(fig)
    files.append('error_vs_time.png')

    # RMS per cell and axis
    labels = list(cells)
    rms = np.array([[np.sqrt(np.nanmean([o.err[i] ** 2 for o in runs])) for i in range(3)] for runs in cells.values()])
    sig = np.array([[np.nanmean([o.sigma[i] for o in runs]) for i in range(3)] for runs in cells.values()])
    fig, ax = plt.subplots(figsize=(max(6.0, 0.55 * len(labels) * 3), 4.2))
    x = np.arange(len(labels))
    for i, a in enumerate(exp.axes):
        ax.bar(x + (i - 1) * 0.27, rms[:, i], 0.27, label=f'{a} RMS')
        ax.plot(x + (i - 1) * 0.27, sig[:, i], 'k_', ms=12)
    ax.set_xticks(x, labels, rotation=35, ha='right', fontsize=7)
    ax.set_ylabel('arcmin at score time (— = mean 1σ)')
    ax.set_yscale('log')
    ax.grid(alpha=0.3, axis='y')
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / 'rms_by_cell.png', dpi=90)
    plt.close(fig)
    files.append('rms_by_cell.png')

    # RMS vs the swept variable, one line per remaining combination
    if exp.sweep:
        groups: dict[tuple, list[tuple[float, np.ndarray]]] = {}
        for runs in cells.values():
            swept = dict(runs[0].spec.values)[exp.sweep]
            if not isinstance(swept, (SupportsFloat, str)):
                raise TypeError(f'{exp.name}: the swept column {exp.sweep} is not a number: {swept!r}')
            key = tuple((k, v) for k, v in runs[0].spec.values if k != exp.sweep)
            groups.setdefault(key, []).append(
                (float(swept), np.sqrt(np.nanmean([o.err ** 2 for o in runs], axis=0))))
        fig, axs = plt.subplots(1, 3, figsize=(13, 3.8), squeeze=False)
        for key, pts in groups.items():
            pts.sort(key=lambda p: p[0])
            xs = [p[0] for p in pts]
            for i in range(3):
                axs[0, i].plot(xs, [p[1][i] for p in pts], 'o-', label=' '.join(f'{k}={v}' for k, v in key) or 'all')
        for i, a in enumerate(exp.axes):
            axs[0, i].set_title(f'{a}: RMS error (arcmin)')
            axs[0, i].set_xlabel(exp.sweep)
            axs[0, i].set_yscale('log')
            axs[0, i].grid(alpha=0.3)
        axs[0, 0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out / f'rms_vs_{exp.sweep}.png', dpi=90)
        plt.close(fig)
        files.append(f'rms_vs_{exp.sweep}.png')

    # average 3-dof NEES over time with its chi-square bounds
    fig, ax = plt.subplots(figsize=(8, 4))
    n_runs = 1
    for label, runs in show:
        n_runs = len(runs)
        k = min(len(o.t_s) for o in runs)
        ne = np.mean([np.sum((o.err_t[:k] / o.sigma_t[:k]) ** 2, axis=1) for o in runs], axis=0)
        ax.plot(runs[0].t_s[:k], ne, lw=0.8, label=label)
    lo, hi = nees_bounds(3, n_runs)
    ax.axhline(lo, color='k', ls='--', lw=0.8)
    ax.axhline(hi, color='k', ls='--', lw=0.8, label=f'95 % bounds ({n_runs} runs, 3 dof)')
    ax.set_yscale('log')
    ax.set_xlabel('time since start (s)')
    ax.set_ylabel(f'average NEES ({exp.quantity}, 3 dof)')
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out / 'nees.png', dpi=90)
    plt.close(fig)
    files.append('nees.png')
    return files


def write_report(out: Path, exp: Experiment, outcomes: list[RunOutcome], seeds: int, first_seed: int) -> Path:
    """Write report.md and its plots into `out`; returns the report's path."""
    cells = cells_of(outcomes)
    files = _plots(out, exp, cells)
    vn = value_names(outcomes)
    if isinstance(exp.score_at, str):
        score = 'at the release (last on-deck sample)' + (f', {exp.score_at[8:]} s after' if exp.score_at[7:] else '')
    else:
        score = f'at t = {exp.score_at} s'
    score_times = sorted({round(o.score_time_s, 3) for o in outcomes})
    md = [f'# {exp.title}', '', exp.description, '',
          f'- Experiment `{exp.name}`, scenario `{exp.scenario}`, {len(cells)} cells × {seeds} seeds '
          f'(seeds {first_seed}-{first_seed + seeds - 1}, the same in every cell), {len(outcomes)} runs, '
          f'batch pipeline; code `{code_version()}`.',
          f'- Scored {score} (actual score times: {", ".join(str(t) for t in score_times[:4])} s): '
          + ('the misalignment estimate against the true master-to-aircraft attitude (mounting and flexure); '
             'arcmin, aircraft axes ROS FLU (roll = x, pitch = y, yaw = z).' if exp.quantity == 'misalignment' else
             'the slave INS attitude error against the aircraft truth, nav frame (E, N, U), arcmin.'),
          '- Base overrides: ' + ', '.join(f'`{k}={v}`' for k, v in exp.base), '',
          '## Results per cell', '',
          'RMS and 95th percentile of |error| over the seeds, the filter\'s mean 1σ, the fraction of runs '
          'inside 2σ (0.95 for an honest filter), the average 3-dof NEES with its 95 % χ² bounds, the mean '
          'normalised innovation squared (NIS; its expectation is the measurement dimension), and the '
          f'median settling time (error stays within {exp.settle_arcmin} arcmin).', '']
    rows = []
    for runs in cells.values():
        err = np.array([o.err for o in runs])
        sig = np.array([o.sigma for o in runs])
        fin = np.all(np.isfinite(err), axis=1) & np.all(np.isfinite(sig), axis=1)
        if not np.any(fin):
            fin[:] = True                       # all diverged: the statistics show it as NaN
        st = [axis_stats(err[fin, i], sig[fin, i]) for i in range(3)]
        ne = float(np.mean([o.nees for o, f in zip(runs, fin) if f]))
        lo, hi = nees_bounds(3, int(np.sum(fin)))
        settle = np.array([o.settle_s for o in runs])
        med = [float(np.median(settle[np.isfinite(settle[:, i]), i])) if np.any(np.isfinite(settle[:, i]))
               else float('nan') for i in range(3)]
        vals = dict(runs[0].spec.values)
        bad = int(np.sum(~np.all(np.isfinite(err), axis=1)))
        if bad:
            vals = {**vals, vn[-1]: f'{vals.get(vn[-1], "")} ({bad} of {len(runs)} diverged)'}
        rows.append([str(vals.get(k, '')) for k in vn]
                    + ['/'.join(_f(s.rms) for s in st), '/'.join(_f(s.p95) for s in st),
                       '/'.join(_f(s.mean_sigma) for s in st), '/'.join(_f(s.in_2sigma, 2) for s in st),
                       f'{_f(ne, 2)} [{_f(lo, 2)}, {_f(hi, 2)}]', _f(float(np.nanmean([o.nis_mean for o in runs])), 2),
                       '/'.join(_f(m, 1) for m in med)])
    ax = '/'.join(a[0] if len(a) > 1 else a for a in exp.axes)
    md.append(_table(vn + [f'RMS {ax}', f'p95 {ax}', f'mean 1σ {ax}', 'in 2σ', 'NEES [95 %]', 'mean NIS',
                           'settle (s)'], rows))
    if exp.references:
        md += ['', '## Beside the paper', '', f'{exp.reference_source}. Ours: the RMS error (or mean 1σ, as the '
               'paper reports) over the seeds of the matching cell. Ratio = |paper| / ours (how many times smaller '
               'ours is).', '']
        rows = []
        for ref in exp.references:
            for label, runs in cells.items():
                if not _matches(dict(runs[0].spec.values), ref.match):
                    continue
                if ref.stat == 'sigma':
                    ours = np.nanmean([o.sigma for o in runs], axis=0)
                else:
                    ours = np.sqrt(np.nanmean([o.err ** 2 for o in runs], axis=0))
                cols = [('mean 1σ' if ref.stat == 'sigma' else 'RMS error')]
                for i in range(3):
                    p = ref.arcmin[i]
                    cols.append('–' if p is None else f'{p:.3g} / {ours[i]:.3g} / {abs(p) / ours[i]:.3g}×')
                rows.append([label] + cols)
        md.append(_table(['cell', 'ours'] + [f'{a}: paper / ours / ratio' for a in exp.axes], rows))
    if exp.notes:
        md += ['', '## Reading', '', exp.notes]
    md += ['', '## Plots', ''] + [f'![{f}]({f})' for f in files]
    md += ['', 'Files: `runs.csv` (one row per run), `summary.csv` (per cell and axis), `meta.json`, '
           '`series.npz` (error and 1σ histories), `timing.json`.', '']
    path = out / 'report.md'
    path.write_text('\n'.join(md))
    return path
