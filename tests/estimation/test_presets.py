"""filter.preset (estimation/presets.py): a grade's densities and priors fill the filter keys
the scenario does not give; and the consistency monitor flags a preset that does not fit the
data: navigation-grade tuning on a MEMS IMU is an ERROR, the MEMS tuning on it is OK with an
honest NEES."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.health import ERROR, OK
from alignment_core.estimation.presets import FILTER_PRESETS
from alignment_core.validation import ConfigError

# the simulated MEMS IMU (sensors/presets.py mems_store) without its accelerometer-triad
# non-orthogonality: the filters have no state for it, and its 60" set a ~1' level floor (docs/engine.md)
MEMS = {'duration_s': 120.0, 'imu.preset': 'mems_store', 'imu.accel_nonorth_arcsec': 0.0,
        'imu.gyro_nonorth_arcsec': 0.0}


def test_a_preset_fills_what_is_not_given_and_explicit_keys_win():
    sc = scenario.load('rigid', overrides={'filter.preset': 'mems', 'filter.arw_dpsh': 0.2})
    want = FILTER_PRESETS['mems']
    assert sc.filter.preset == 'mems' and sc.filter.arw_dpsh == 0.2
    for k in ('gyro_bias_sigma_dph', 'accel_bias_sigma_ug', 'vrw_ugpshz', 'gyro_bias_rw_dphps', 'accel_bias_rw_ugps'):
        assert getattr(sc.filter, k) == want[k]
    plain = scenario.load('rigid').filter
    for k in want:                                         # no preset: the defaults as they were
        assert getattr(plain, k) == getattr(FilterConfig(), k)
    with pytest.raises(ConfigError, match="filter.preset: unknown preset 'consumer'"):
        scenario.load('rigid', overrides={'filter.preset': 'consumer'})


def _run(preset: str, seed: int):
    sc = scenario.load('rigid', overrides={**MEMS, 'filter.preset': preset}, seed=seed)
    inp = pipeline.simulate(sc)
    f = pipeline.align(sc, inp)
    e = f.outputs[-1]
    err = e.misalignment - inp.sensor_truth['mounting']
    return f, float(np.sum((err / e.misalignment_sigma) ** 2))


def test_navigation_tuning_on_a_mems_imu_is_flagged():
    f, nees = _run('navigation', 1)
    d = f.diagnostics()
    assert d.level == ERROR and 'inconsistent' in d.flags and not f.healthy
    assert nees > chi2.isf(0.001, 3)                      # and it is indeed wrong


def test_mems_tuning_on_a_mems_imu_is_ok_and_honest():
    """3 seeds: every run OK (no NIS window in a row failing), whiteness passing, and the average
    3-dof NEES inside the 95 % chi-square bounds of 9 dof / 3."""
    nees = []
    for seed in (1, 2, 3):
        f, n = _run('mems', seed)
        d = f.diagnostics()
        assert d.level == OK and f.healthy, (seed, d.message)
        assert f.whiteness.failures <= 1
        nees.append(n)
    lo, hi = chi2.ppf(0.025, 9) / 3, chi2.ppf(0.975, 9) / 3
    assert lo < np.mean(nees) < hi, nees
