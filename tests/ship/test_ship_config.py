"""Ship configuration: validation errors, dispatch by mode, paper mode unchanged, and the
low-frequency straight course (its position is the integral of its velocity)."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.geometry import earth
from alignment_core.ship.motion import make_motion
from alignment_core.ship.paper import PaperShipMotion
from alignment_core.ship.spectral import SpectralShipMotion, StraightCourse
from alignment_core.units import DEG
from alignment_core.validation import ConfigError


@pytest.mark.parametrize('overrides,message', [
    ({'ship.sea_state': 12}, 'sea_state must be a WMO code 0-9, got 12'),
    ({'ship.speed_kn': -3.0}, 'speed_kn must be in'),
    ({'ship.rao_source': '/nonexistent/ship.mat'}, 'RAO file not found'),
    ({'ship.spectrum': 'pm'}, 'ship.spectrum: must be one of'),
    ({'ship.hs_m': -1.0}, 'hs_m must be in'),
    ({'ship.n_frequencies': 0}, 'n_frequencies'),
    ({'ship.mode': 'sinusoid'}, 'ship.mode: must be one of'),
])
def test_invalid_spectral_configs_fail_clearly(overrides, message):
    with pytest.raises(ConfigError, match=message):
        scenario.load('deck', {'ship.mode': 'spectral', **overrides})


def test_dispatch_by_mode():
    sc = scenario.load('deck')
    assert sc.ship.mode == 'paper' and isinstance(pipeline.ship_source(sc), PaperShipMotion)
    sc = scenario.load('deck', {'ship.mode': 'spectral', 'ship.sea_state': 8})
    src = pipeline.ship_source(sc)
    assert isinstance(src, SpectralShipMotion) and src.sea.hs_m == 11.5 and src.sea.tp_s == 16.4
    # beyond the WMO codes neither mode has a sea
    with pytest.raises(ConfigError, match='sea_state'):
        scenario.load('deck', {'ship.sea_state': 10})


def test_paper_mode_is_unchanged():
    """Numbers produced by the paper-mode ship before the spectral mode existed (commit
    301e940), compared bit for bit."""
    t = np.array([0.0, 12.34, 299.99])
    sc = scenario.load('deck', {'ship.sea_state': 5, 'seed': 7})
    s = make_motion(sc.ship, sc.seed).samples(t, 1000, 10)
    np.testing.assert_array_equal(s[1].q_nb, [0.006855536188744811, 0.019266949835537263,
                                              0.5112608086284454, 0.8591822692701405])
    np.testing.assert_array_equal(s[1].w_b, [0.03338245040913687, -0.03533565228068215,
                                             0.03754685636188148])
    np.testing.assert_array_equal(s[2].a_b, [0.04420772856395579, -0.014692128494115634,
                                             0.8747982500378224])
    np.testing.assert_array_equal(s[2].p_w, [771.5045955173463, 1336.5603561868595,
                                             -1.6071748372380203])


@pytest.mark.parametrize('heading_deg', [0.0, 30.0, 90.0, 200.0])
def test_straight_course_position_integrates_velocity(heading_deg):
    """d(lat)/dt = v_N / R_M(lat), d(lon)/dt = v_E / (R_N cos lat) along an hour at 30 kn
    (central differences, independent of the closed-form integration)."""
    lat0, lon0 = 60.0 * DEG, 10.0 * DEG
    c = StraightCourse(lat0, lon0, heading_deg * DEG, 30 * 0.514444)
    t = np.linspace(0.0, 3600.0, 3601)
    lat, lon = c.geodetic(t)
    assert lat[0] == lat0 and lon[0] == lon0
    h = 0.5
    lp, op = c.geodetic(t + h)
    lm, om = c.geodetic(t - h)
    r_m, r_n = earth.radii(lat)
    np.testing.assert_allclose((lp - lm) / (2 * h) * r_m, c.v_n[1], atol=1e-7)
    np.testing.assert_allclose((op - om) / (2 * h) * r_n * np.cos(lat), c.v_n[0], atol=1e-7)


def test_monte_carlo_sea_draw_in_the_ship_model():
    """`sea_draw` draws Hs and Tp within the sea state's bin from their own stream: the wave
    phases (stream 'ship_waves') stay those of the seed."""
    cfgs = [scenario.load('deck', {'ship.mode': 'spectral', 'ship.sea_state': 5, 'ship.sea_draw': True,
                                   'seed': s}).ship for s in range(1, 9)]
    seas = [SpectralShipMotion(c, s).sea for s, c in enumerate(cfgs, start=1)]
    assert all(2.5 <= x.hs_m <= 4.0 and 8.3 <= x.tp_s <= 15.5 for x in seas)
    assert len({x.hs_m for x in seas}) == len(seas)
    fixed = SpectralShipMotion(scenario.load('deck', {'ship.mode': 'spectral', 'ship.sea_state': 5,
                                                      'seed': 3}).ship, 3)
    assert fixed.sea.hs_m == 3.25 and fixed.sea.tp_s == 9.7
    drawn = SpectralShipMotion(cfgs[2], 3)
    np.testing.assert_array_equal(drawn.comps.phase, fixed.comps.phase)
