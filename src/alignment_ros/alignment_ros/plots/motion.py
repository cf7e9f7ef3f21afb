"""The ship's motion (roll, pitch from /ship/odom's attitude w.r.t. the local-level ENU frame;
heave: its height in the world frame) and the aircraft's velocity relative to the deck measured
by the LDV (/ldv/twist, ship axes; samples flagged as no measurement left out)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import style
from .series import RunSeries

DEG = 180.0 / np.pi


def motion(s: RunSeries, path: Path) -> Path | None:
    if s.ship is None and s.ldv is None:
        return None
    rows = (3 if s.ship is not None else 0) + (1 if s.ldv is not None else 0)
    fig, axs = style.figure(rows, 1, 1.7)
    r = 0
    if s.ship is not None:
        t = s.ship['t_s']
        for key, label, scale in (('roll_rad', 'roll (deg)', DEG), ('pitch_rad', 'pitch (deg)', DEG),
                                  ('heave_m', 'heave: height (m)', 1.0)):
            axs[r, 0].plot(t, s.ship[key] * scale, lw=0.9, color='tab:blue')
            axs[r, 0].set_ylabel(label)
            r += 1
        axs[0, 0].set_title('ship (/ship/odom)')
    if s.ldv is not None:
        ax = axs[r, 0]
        t, v, ok = s.ldv['t_s'], s.ldv['v_mps'], s.ldv['valid']
        if ok.any():
            for k, name in enumerate(('x (fwd)', 'y (left)', 'z (up)')):
                ax.plot(t[ok], v[ok, k], '.', ms=2, color=style.AXIS_COLORS[k], label=name)
            ax.legend(loc='upper left', ncol=3, markerscale=4)
        else:
            style.note(ax, 'no valid LDV measurement')
        ax.set_ylabel('deck velocity (m/s)')
        ax.set_title(f'aircraft relative to the deck (/ldv/twist, ship axes): {100 * ok.mean():.0f} % of '
                     f'the samples valid')
    return style.finish(fig, axs, "Ship motion and the aircraft's deck velocity", path)
