"""The filters' innovation consistency from /diagnostics: each update's NIS (the filter reports
the last one with every diagnostics message) against the two-sided 95 % chi-square band of its
degrees of freedom, and the consistency monitor's windowed NIS per degree of freedom against
the monitor's own one-sided bound (the /diagnostics key nis_window_bound) and the 95 % band,
with the monitor's verdict (its level, windows failed) in the title.

The diagnostics give the window's bound per dof, not its dof D; with the monitor's window size
and tail probability (the run's scenario.yaml, else the library defaults) D is the one whose
chi2 quantile gives that bound, and an update's dof is D / window."""
from __future__ import annotations

from pathlib import Path

import numpy as np

# the chi-square quantiles from scipy.special, what scipy.stats' chi2.isf and chi2.ppf call (the
# same numbers): scipy.stats alone would add ~0.4 s to every run's report
from scipy.special import chdtri, gammaincinv

from alignment_core.estimation.config import FilterConfig

from . import style
from .series import Diagnostic, RunSeries

LEVEL_NAMES = ('OK', 'WARN', 'ERROR', 'STALE')
LEVEL_COLORS = ('tab:green', 'tab:orange', 'tab:red', 'tab:grey')
STATUS_TITLES = {'alignment_filter': 'alignment filter', 'air_data_filter': 'air-data filter'}


def monitor_settings(scenario: dict | None = None) -> tuple[int, float]:
    """(window updates, warn_p) of the consistency monitor: the scenario's filter section, else
    the library defaults."""
    f = (scenario or {}).get('filter') or {}
    d = FilterConfig()
    return (int(f.get('consistency_window_updates', d.consistency_window_updates)),
            float(f.get('consistency_warn_p', d.consistency_warn_p)))


def _central_95(dof: int) -> np.ndarray:
    """The 2.5 % and 97.5 % quantiles of chi2(dof) (chi2.ppf's formula)."""
    return 2.0 * gammaincinv(dof / 2, np.array([0.025, 0.975]))


def update_dof(bound_per_dof: float, window: int, warn_p: float) -> int | None:
    """The dof of one update, from a window's published bound per dof (None if no dof fits)."""
    if not np.isfinite(bound_per_dof) or bound_per_dof <= 0:
        return None
    dofs = np.arange(window, 64 * window + 1, window)
    per = chdtri(dofs, warn_p) / dofs
    k = int(np.argmin(np.abs(per - bound_per_dof)))
    return int(dofs[k] // window) if abs(per[k] - bound_per_dof) <= 2e-3 * bound_per_dof else None


def verdict(d: Diagnostic) -> str:
    """The monitor's verdict at the end: its level and failed windows, health."""
    level = int(d.levels[-1]) if len(d.levels) else 3
    last = d.values[-1] if d.values else {}
    parts = [f'final level {LEVEL_NAMES[min(level, 3)]}']
    if 'nis_windows' in last:
        parts.append(f"{last.get('nis_windows_failed', '?')} of {last['nis_windows']} NIS windows failed")
    if last.get('healthy') == 'false':
        parts.append('UNHEALTHY')
    return ', '.join(parts)


def _panel_updates(ax, d: Diagnostic, dof: int | None) -> None:
    nis = d.number('nis')
    ok = np.isfinite(nis) & (nis > 0)
    if not ok.any():
        style.note(ax, 'no NIS in /diagnostics')
        return
    ax.semilogy(d.t_s[ok], nis[ok], '.', ms=3, color='tab:blue', label='NIS of the last update')
    if dof is not None:
        lo, hi = _central_95(dof)
        ax.axhspan(lo, hi, color='tab:green', alpha=0.12, label=f'95 % band, χ²({dof})')
        ax.axhline(dof, color='tab:green', lw=0.8, ls='--')
        inside = np.mean((nis[ok] >= lo) & (nis[ok] <= hi))
        ax.set_title(f'{100 * inside:.0f} % of the sampled updates inside the band (95 % expected)')
    ax.set_ylabel('NIS (-)')
    ax.legend(loc='best', ncol=2)


def _panel_windows(ax, d: Diagnostic, window: int, dof: int | None) -> None:
    mean, bound = d.number('nis_window_mean'), d.number('nis_window_bound')
    ok = np.isfinite(mean)
    if not ok.any():
        style.note(ax, 'no completed NIS window')
        return
    ax.plot(d.t_s[ok], mean[ok], '-o', ms=2.5, lw=1.0, color='tab:blue', label='window mean NIS / dof')
    ax.plot(d.t_s[ok], bound[ok], color='tab:red', lw=1.0, label='monitor bound (fails above)')
    if dof is not None:
        n = window * dof
        lo, hi = _central_95(n) / n
        ax.axhspan(lo, hi, color='tab:green', alpha=0.12, label=f'95 % band, χ²({n}) / {n}')
    ax.axhline(1.0, color='grey', lw=0.6)
    ax.set_ylabel('NIS / dof (-)')
    ax.legend(loc='lower left', bbox_to_anchor=(0.0, 1.0), ncol=3, frameon=False)


def _levels(ax, d: Diagnostic) -> None:
    """The diagnostics level as a strip of colour along the bottom of the panel."""
    for i in range(len(d.t_s)):
        t1 = d.t_s[i + 1] if i + 1 < len(d.t_s) else d.t_s[i]
        ax.axvspan(d.t_s[i], t1, ymin=0.0, ymax=0.03, color=LEVEL_COLORS[min(int(d.levels[i]), 3)], lw=0)


def nis(s: RunSeries, path: Path, scenario: dict | None = None) -> Path | None:
    names = [n for n in s.diagnostics if np.isfinite(s.diagnostics[n].number('nis')).any()]
    if not names:
        return None
    window, warn_p = monitor_settings(scenario if scenario is not None else s.scenario)
    windows = {n: bool(np.isfinite(s.diagnostics[n].number('nis_window_mean')).any()) for n in names}
    fig, axs = style.figure(sum(1 + w for w in windows.values()), 1, 2.0)
    r = 0
    for name in names:
        d = s.diagnostics[name]
        bounds = d.number('nis_window_bound')
        b = bounds[np.isfinite(bounds)]
        dof = update_dof(float(b[-1]), window, warn_p) if b.size else None
        top = axs[r, 0]
        _panel_updates(top, d, dof)
        sub = top.get_title() or 'no band: the dof of an update is not published'
        top.set_title(f'{STATUS_TITLES.get(name, name)}: {verdict(d)}\n{sub}', fontsize=9)
        if windows[name]:
            r += 1
            _panel_windows(axs[r, 0], d, window, dof)
        _levels(axs[r, 0], d)
        r += 1
    return style.finish(fig, axs, 'Innovation consistency (level strip: green OK, orange WARN, red ERROR)',
                        path)
