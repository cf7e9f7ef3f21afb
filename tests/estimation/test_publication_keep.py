"""EstimateMaker.keep (estimation/publication.py): a non-finite output is a breakdown
(docs/engine.md), the odometry it makes (position, velocity, rate and their covariances) as much
as the covariance and the misalignment, so no output at OK carries NaN."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filter_factory import make_filter
from alignment_core.estimation.matching import LiveSolution, MatchResults
from alignment_core.estimation.models import make_model
from alignment_core.estimation.publication import EstimateMaker, OdometryMaker
from alignment_core.geometry import earth
from alignment_core.navigation.history import SlaveHistory
from alignment_core.navigation.strapdown import NavState, Strapdown

LAT = 0.7
PLANE = earth.TangentPlane(LAT, 2.0, 0.0)


def _setup(nav: dict | None = None, gyro: np.ndarray | None = None, p_dv_offdiag: float = 0.0
           ) -> tuple[EstimateMaker, LiveSolution, MatchResults]:
    """A vm15 maker and a live solution at rest at the plane's origin; nav: NavState fields to
    replace, p_dv_offdiag: a velocity cross-covariance (not in sigma: only the twist covariance
    sees it)."""
    cfg = FilterConfig()
    model = make_model(cfg)
    st = NavState(q_nb=np.array([0.0, 0.0, 0.0, 1.0]), v_n=np.zeros(3), lat=LAT, lon=2.0, h=0.0)
    st = dataclasses.replace(st, **(nav or {}))
    p = model.initial_covariance()
    p[3, 4] = p[4, 3] = p_dv_offdiag
    kf = make_filter(cfg, np.zeros(model.n), p, model.kinds)
    live = LiveSolution(Strapdown(st), kf, 0, SlaveHistory(int(0.2e9)), gyro=gyro)
    res = MatchResults(mu=np.zeros(3), mu_sigma=np.full(3, 1e-3), x=np.zeros(model.n))
    maker = EstimateMaker(model, OdometryMaker(model, PLANE, 0.01, cfg.arw_dpsh, cfg.gyro_bias_sigma_dph))
    return maker, live, res


def test_a_finite_solution_is_kept_with_its_odometry():
    maker, live, res = _setup(gyro=np.full(3, 1e-5))
    odo = maker.keep(live, res)
    assert odo is not None and maker.held is not None and maker.held_state is not None
    assert np.all(np.isfinite(odo.p_w)) and np.all(np.isfinite(odo.twist_cov))


@pytest.mark.parametrize('bad', [
    dict(nav={'v_n': np.array([math.nan, 0.0, 0.0])}),          # velocity (and position through it)
    dict(nav={'lat': math.nan}),                                # position
    dict(nav={'h': math.inf}),                                  # position
    dict(gyro=np.array([0.0, math.inf, 0.0])),                  # body rate
    dict(p_dv_offdiag=math.nan),                                # twist covariance only
], ids=['velocity', 'latitude', 'height', 'rate', 'twist_cov'])
def test_non_finite_odometry_is_a_breakdown_and_nothing_is_kept(bad):
    """The sweep's case (inflight, stf, 30 s, seed 1): the slave diverged to a NaN position,
    velocity and rate while the covariance and the misalignment were still finite; that output
    was healthy at OK. Now keep() refuses it (the engine counts a breakdown) and holds what it
    held before."""
    maker, live, res = _setup(**bad)
    with np.errstate(invalid='ignore', over='ignore'):
        assert maker.keep(live, res) is None
    assert maker.held is None and maker.held_state is None


def test_a_negative_variance_is_numpys_to_judge_warning_and_all():
    """keep takes P's attitude block and sqrt(diag P) in one compiled call; a covariance it finds
    not finite goes through numpy's lines again, so a negative variance warns (or raises under
    np.errstate) as numpy's square root does, and nothing is kept."""
    maker, live, res = _setup()
    p = live.kf.P.copy()
    p[7, 7] = -1.0
    live.kf.P = p
    with pytest.warns(RuntimeWarning, match='invalid value'):
        assert maker.keep(live, res) is None
    with np.errstate(invalid='raise'), pytest.raises(FloatingPointError):
        maker.keep(live, res)
    assert maker.held is None


@pytest.mark.parametrize('shape', [(0, 2), (2, 2), (0, -2)], ids=['wider', 'larger', 'narrower'])
def test_a_covariance_of_another_shape_is_read_by_numpy(shape):
    """A P that is not the model's n x n (a filter handed a wrong one) is never read by the
    compiled call (which does not check bounds): numpy's lines read it as before, sigma the
    root of its diagonal, however long."""
    maker, live, res = _setup()
    n = live.kf.P.shape[0]
    odd = np.eye(n + shape[0], n + shape[1]) * 1e-4
    live.kf.P = odd
    odo = maker.keep(live, res)
    assert odo is not None and maker.held is not None
    assert maker.held[1].tobytes() == np.sqrt(np.diag(odd)).tobytes()
