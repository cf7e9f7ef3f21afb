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


def _series(lab: Labelled | None, row: str, label: str) -> np.ndarray | None:
    return None if lab is None else lab.column(row, label)


def air_data(s: RunSeries, path: Path) -> Path | None:
    est, truth = s.air, s.air_truth
    if est is None and truth is None:
        return None
    fig, axs = style.figure(3, 2, 2.0)
    for n, (label, ylabel, scale) in enumerate(PANELS):
        ax = axs[n % 3, n // 3]
        v = _series(est, 'value', label)
        sig = _series(est, 'sigma', label)
        tv = _series(truth, 'value', label)
        if v is not None:
            ax.plot(est.t_s, v * scale, color='tab:blue', lw=1.0, label='estimate')
            if sig is not None:
                ax.fill_between(est.t_s, (v - 3 * sig) * scale, (v + 3 * sig) * scale, color='tab:blue',
                                alpha=0.2, lw=0, label='±3σ')
        if tv is not None:
            ax.plot(truth.t_s, tv * scale, 'k--', lw=0.9, label='truth')
        if v is None and tv is None:
            style.note(ax, f'no {label}')
        elif v is not None:
            tvi = None if tv is None else np.interp(est.t_s, truth.t_s, tv)
            band = [] if sig is None else [v - 3 * sig, v + 3 * sig]
            lim = style.limits([x * scale for x in (v, tvi, *band) if x is not None], est.t_s, skip=0.25)
            if lim:
                ax.set_ylim(*lim)
        ax.set_ylabel(ylabel)
        if n == 0:
            ax.legend(loc='upper right', ncol=3)
    return style.finish(fig, axs, 'Air data (estimate ±3σ; truth dashed)', path)
