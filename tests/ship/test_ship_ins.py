"""INS consistency of the spectral ship (the critical check): noise-free slave IMU increments
(pipeline.SlaveImuStage with the IMU's noise and biases off) integrated by the strapdown from
the true initial state must reproduce the true attitude (< 1e-6 rad) and velocity
(< 1e-3 m/s). Sea state 6, 20 kn, bow-quartering seas from port (all six DOF excited).

600 s here to keep the suite fast; `python bench/ship_motion.py --ins` runs the hour.
"""
from __future__ import annotations

import numpy as np
import pytest
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, strapdown_errors

from alignment_core.config import scenario

SPECTRAL_SS6 = {'ship.mode': 'spectral', 'ship.sea_state': 6, 'ship.speed_kn': 20.0,
                'ship.wave_heading_deg': 120.0}


@pytest.mark.parametrize('lever_arm', [[90.0, -40.0, 15.0], [0.0, 0.0, 0.0]],
                         ids=['aircraft-100m-from-master', 'master-point'])
def test_strapdown_reproduces_spectral_ship_truth(lever_arm):
    sc = scenario.load('deck_paper', {**NOISE_OFF, **SPECTRAL_SS6, 'aircraft.lever_arm_m': lever_arm,
                                'duration_s': 600.0})
    att, vel, truth = strapdown_errors(sc)
    assert len(att) == 60000 and np.all(truth['on_deck'])
    # the deck really moves: tens of cm/s and a degree of roll at the aircraft
    w = np.linalg.norm(truth['w_b'], axis=-1)
    assert w.max() > 0.5 * np.pi / 180.0 / 20.0
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'
