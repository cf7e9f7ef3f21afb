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

from alignment_core.estimation.models.base import Corrections, ErrorModel, Match, Measurement, ModelWrapper


class YawMatching(ModelWrapper):
    """`base` (velocity rows + attitude rows for all three nav axes) keeping the U attitude row."""

    def __init__(self, base: ErrorModel) -> None:
        if tuple(base.attitude_rows) != (0, 1, 2):
            raise ValueError(f'yaw matching needs a model with attitude rows (seed003_21/24), not {base.name}')
        super().__init__(base, '+yaw_only')
        self.attitude_rows = (2,)
        nv = len(base.velocity_rows)
        self.keep = np.array(list(range(nv)) + [nv + 2])

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        meas = self.base.measurement(m, corr)
        k = self.keep
        return Measurement(meas.z[k], meas.matrix()[k], meas.r[np.ix_(k, k)])
