"""Ship configuration: validation errors, dispatch by mode, the paper mode is seed 002's
sinusoids (Table 3 amplitudes at their periods), and the low-frequency straight course (its
position is the integral of its velocity)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.geometry import earth
from alignment_core.ship.motion import make_motion
from alignment_core.ship.paper import PaperShipMotion
from alignment_core.ship.spectral import SpectralShipMotion
from alignment_core.ship.track import StraightCourse
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
        scenario.load('deck_paper', {'ship.mode': 'spectral', **overrides})


def test_dispatch_by_mode():
    sc = scenario.load('deck_paper')
    assert sc.ship.mode == 'paper' and isinstance(pipeline.ship_source(sc), PaperShipMotion)
    sc = scenario.load('deck_paper', {'ship.mode': 'spectral', 'ship.sea_state': 8})
    src = pipeline.ship_source(sc)
    assert isinstance(src, SpectralShipMotion) and src.sea.hs_m == 11.5 and src.sea.tp_s == 16.4
    # beyond the WMO codes neither mode has a sea
    with pytest.raises(ConfigError, match='sea_state'):
        scenario.load('deck_paper', {'ship.sea_state': 10})


def _sinusoid_fit(t, y, period):
    """Least squares of y on [1, sin wt, cos wt]: (offset, amplitude, phase, max residual)."""
    w = 2.0 * np.pi / period
    a = np.column_stack([np.ones_like(t), np.sin(w * t), np.cos(w * t)])
    c, *_ = np.linalg.lstsq(a, y, rcond=None)
    return c[0], float(np.hypot(c[1], c[2])), float(np.arctan2(c[2], c[1])), float(np.max(np.abs(a @ c - y)))


def test_paper_mode_is_seed_002s_sinusoids():
    """Seed 002's ship (eq 18) at sea state 5, heading 30 deg, 10 kn: each Euler angle is one
    sinusoid with the paper's Table 3 amplitude (roll 5.62, pitch 2.91, yaw 3.36 deg) at its
    period (roll at the natural period 17 s, pitch, yaw and heave 7.5, 9.0 and 8.0 s); yaw about
    the course (ENU yaw = 90 deg - heading); the vertical velocity is the heave rate, amplitude
    (Hs / 2) w with Bales' mean Hs 3.25 m; the horizontal velocity is the course's. Phases are
    random per axis: two seeds differ in every one."""
    t = np.arange(0.0, 300.0, 0.25)
    speed = 10.0 * 0.514444          # m/s: the project knot (1852 m / 3600 s to six digits, units.KNOT)
    v_course = speed * np.array([np.sin(np.radians(30.0)), np.cos(np.radians(30.0))])
    phases = []
    for seed in (7, 8):
        sc = scenario.load('deck_paper', {'ship.sea_state': 5, 'seed': seed})
        assert sc.ship.mode == 'paper' and sc.ship.heave and sc.ship.motion_scale == 1.0
        assert (sc.ship.heading_deg, sc.ship.speed_kn) == (30.0, 10.0)
        s = make_motion(sc.ship, sc.seed).samples(t, 0, 250_000_000)
        rot = Rotation.from_quat([x.q_nb for x in s])
        yaw, pitch, roll = np.unwrap(rot.as_euler('ZYX'), axis=0).T
        v_n = rot.apply([x.v_b for x in s])
        ph = []
        for y, amp_want, period, offset in ((roll, np.radians(5.62), 17.0, 0.0),
                                            (pitch, np.radians(2.91), 7.5, 0.0),
                                            (yaw, np.radians(3.36), 9.0, np.radians(90.0 - 30.0)),
                                            (v_n[:, 2], 0.5 * 3.25 * 2.0 * np.pi / 8.0, 8.0, 0.0)):
            c0, amp, phase, resid = _sinusoid_fit(t, y, period)
            assert c0 == pytest.approx(offset, abs=1e-9)
            assert amp == pytest.approx(amp_want, rel=1e-9)
            assert resid < 1e-9
            ph.append(phase)
        np.testing.assert_allclose(v_n[:, :2], np.broadcast_to(v_course, (len(t), 2)), rtol=0, atol=1e-9)
        phases.append(ph)
    assert np.min(np.abs(np.subtract(*phases))) > 1e-3


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
    cfgs = [scenario.load('deck_paper', {'ship.mode': 'spectral', 'ship.sea_state': 5, 'ship.sea_draw': True,
                                   'seed': s}).ship for s in range(1, 9)]
    seas = [SpectralShipMotion(c, s).sea for s, c in enumerate(cfgs, start=1)]
    assert all(2.5 <= x.hs_m <= 4.0 and 8.3 <= x.tp_s <= 15.5 for x in seas)
    assert len({x.hs_m for x in seas}) == len(seas)
    fixed = SpectralShipMotion(scenario.load('deck_paper', {'ship.mode': 'spectral', 'ship.sea_state': 5,
                                                      'seed': 3}).ship, 3)
    assert fixed.sea.hs_m == 3.25 and fixed.sea.tp_s == 9.7
    drawn = SpectralShipMotion(cfgs[2], 3)
    np.testing.assert_array_equal(drawn.comps.phase, fixed.comps.phase)
