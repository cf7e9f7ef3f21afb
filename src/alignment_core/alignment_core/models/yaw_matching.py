"""Velocity + yaw matching: an attitude-matching model reduced to its heading row
(`filter.attitude_match_axes: yaw`).

Seed 003's attitude rows compare the slave's attitude with the master's carried through the
estimated mounting (models/seed003.py); keeping only the vertical (nav U) row matches heading
alone, the classic velocity + yaw match for when the master's level is poorer than its heading
or the deck's flexure about the level axes is not trusted. The mounting states stay: without
them a heading match would force the slave onto the master's heading, wrong by the unknown
mounting yaw, which is exactly what the filter is there to estimate.
"""
from __future__ import annotations

import numpy as np

from ..strapdown import NavState
from .base import Corrections, ErrorModel, Match, Measurement, Propagation


class YawMatching(ErrorModel):
    """`base` (velocity rows + attitude rows for all three nav axes) keeping the U attitude row."""

    def __init__(self, base: ErrorModel) -> None:
        if tuple(base.attitude_rows) != (0, 1, 2):
            raise ValueError(f'yaw matching needs a model with attitude rows (seed003_21/24), not {base.name}')
        self.base = base
        self.name = base.name + '+yaw_only'
        self.labels, self.kinds, self.attitude = base.labels, base.kinds, base.attitude
        self.velocity_rows = base.velocity_rows
        self.attitude_rows = (2,)
        nv = len(base.velocity_rows)
        self.keep = np.array(list(range(nv)) + [nv + 2])

    def initial_covariance(self) -> np.ndarray:
        return self.base.initial_covariance()

    def continuous(self, p: Propagation) -> np.ndarray:
        return self.base.continuous(p)

    def transition(self, p: Propagation) -> np.ndarray:
        return self.base.transition(p)

    def process_noise(self, h: float) -> np.ndarray:
        return self.base.process_noise(h)

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        z, h, r, _ = self.base.measurement(m, corr)
        k = self.keep
        return Measurement(z[k], h[k], r[np.ix_(k, k)])

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        return self.base.feedback(x, p, m, nav, corr)

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return self.base.misalignment(x, p, m, nav, corr)
