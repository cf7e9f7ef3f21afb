"""Air data (/air_data/state, and /truth/air_data/state when recorded): Mach, angle of attack,
sideslip and the wind (ENU, blowing to), each estimate with its ±3σ band and the truth."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import style
from .series import Labelled, RunSeries

DEG = 180.0 / np.pi
PANELS = (('mach', 'Mach (-)', 1.0), ('alpha_rad', 'alpha (deg)', DEG), ('beta_rad', 'beta (deg)', DEG),
          ('wind_east_mps', 'wind east (m/s)', 1.0), ('wind_north_mps', 'wind north (m/s)', 1.0),
          ('wind_up_mps', 'wind up (m/s)', 1.0))


def _series(lab: Labelled | None, row: str, label: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(the stream's stamps t_s, the label's column of the row), None without the stream, row or label."""
    if lab is None:
        return None
    column = lab.column(row, label)
    return None if column is None else (lab.t_s, column)


def air_data(s: RunSeries, path: Path) -> Path | None:
    est, truth = s.air, s.air_truth
    if est is None and truth is None:
        return None
    fig, axs = style.figure(3, 2, 2.0)
    for n, (label, ylabel, scale) in enumerate(PANELS):
        ax = axs[n % 3, n // 3]
        est_series = _series(est, 'value', label)
        sig_series = _series(est, 'sigma', label)
        truth_series = _series(truth, 'value', label)
        sig = None if sig_series is None else sig_series[1]
        if est_series is not None:
            est_t_s, v = est_series
            ax.plot(est_t_s, v * scale, color='tab:blue', lw=1.0, label='estimate')
            if sig is not None:
                ax.fill_between(est_t_s, (v - 3 * sig) * scale, (v + 3 * sig) * scale, color='tab:blue',
                                alpha=0.2, lw=0, label='±3σ')
        if truth_series is not None:
            truth_t_s, tv = truth_series
            ax.plot(truth_t_s, tv * scale, 'k--', lw=0.9, label='truth')
        if est_series is None and truth_series is None:
            style.note(ax, f'no {label}')
        elif est_series is not None:
            est_t_s, v = est_series
            tvi = None if truth_series is None else np.interp(est_t_s, *truth_series)
            band = [] if sig is None else [v - 3 * sig, v + 3 * sig]
            lim = style.limits([x * scale for x in (v, tvi, *band) if x is not None], est_t_s, skip=0.25)
            if lim:
                ax.set_ylim(*lim)
        ax.set_ylabel(ylabel)
        if n == 0:
            ax.legend(loc='upper right', ncol=3)
    return style.finish(fig, axs, 'Air data (estimate ±3σ; truth dashed)', path)
