"""The tightly coupled air-data estimator: its measurement model against the port model at the
true air data, and its estimates on a synthetic flight against the truth, within their sigma."""
from __future__ import annotations

import math

import ambiance
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.air_data_flight import air_angles_frd, flight

from alignment_core.air_data.atmosphere import Atmosphere
from alignment_core.air_data.day_offsets import DayOffsets
from alignment_core.air_data.ports import PortModel
from alignment_core.estimation.air_data.config import AirDataFilterConfig
from alignment_core.estimation.air_data.inputs import InsAt
from alignment_core.estimation.air_data.port_prediction import PortPrediction, StateLayout
from alignment_core.estimation.air_data.tight_form import TightAirDataFilter
from alignment_core.estimation.air_data.turbulence_model import TurbulenceModel


def test_prediction_is_the_port_model_at_the_true_air_data():
    """h(x) with wind w, offsets s and dT, biases b: the port model at the alpha, beta (textbook
    FRD formulas), Mach (speed of sound of T_std + dT) and p_inf = p_day(h; dT) (1 + s) of that
    state, p_day the hydrostatic pressure of the warmer day (atmosphere.Atmosphere)."""
    model, lay = PortModel(), StateLayout(5, turbulence=True)
    c_bn = Rotation.from_euler('ZYX', [1.2, -0.2, 0.3]).as_matrix()
    v_g, h = np.array([150.0, 40.0, -5.0]), 8000.0
    x = np.zeros(lay.size)
    x[lay.wind], x[lay.turb] = (10.0, -4.0, 0.5), (0.7, 0.2, -0.3, 0.4, 0.1)
    turb_map = TurbulenceModel('moderate').at(h, v_g, 150.0)[0]                  # (3, 5): state -> ENU
    air_mass = np.array([10.0, -4.0, 0.5]) + turb_map @ x[lay.turb]
    x[lay.static], x[lay.temperature] = 0.004, 7.0
    x[lay.bias] = (3.0, -2.0, 1.0, 0.0, 5.0)
    x[lay.noise] = (0.5, 0.0, -1.0, 2.0, 0.0)
    ins = InsAt(np.repeat(c_bn[None], 5, 0), np.repeat(v_g[None], 5, 0), np.full(5, h))
    pred = PortPrediction(model, lay, np.arange(5), ins, np.repeat(turb_map[None], 5, 0))(x[None, :])[0]
    atm = ambiance.Atmosphere(h)
    p_inf = float(Atmosphere(h, DayOffsets(delta_t_k=7.0)).pressure) * 1.004
    a = math.sqrt(1.4 * 287.05287 * (float(atm.temperature[0]) + 7.0))
    speed, alpha, beta = air_angles_frd(c_bn.T @ (v_g - air_mass))
    expected = model.pressures(alpha, beta, speed / a, p_inf) + x[lay.bias] + x[lay.noise]
    np.testing.assert_allclose(pred, expected, rtol=5e-6)     # ambiance's six-digit base pressures


def _run(algorithm, frames, **cfg):
    f = TightAirDataFilter(AirDataFilterConfig(algorithm=algorithm, lag_s_sea_level=0.0, **cfg), PortModel(), 0.1)
    rows = []
    for fr in frames:
        f.push_ins(fr.ins)
        f.push_frame(fr.t, fr.pressures)
        e = f.estimate()
        rows.append((fr, e))
    return f, rows


@pytest.mark.parametrize('algorithm', ['ekf', 'ckf'])
def test_estimates_track_the_truth_within_their_sigma(algorithm):
    """Level flight at 10 km, Mach 0.8, 5 m/s crosswind, 20 Pa first-order Gauss-Markov port noise
    (lag-1 correlation 0.5): after 60 s, alpha/beta/Mach and the wind inside 4 sigma at every
    frame, and the angle errors near the single-frame Cramer-Rao bound (0.07 deg at 20 Pa) divided
    by the averaging the correlated noise allows."""
    frames = flight(duration_s=200.0, rho=0.5)
    f, rows = _run(algorithm, frames, port_correlation=0.5)
    assert f.counts['gated'] == 0 and f.excluded_ports == ()
    late = [(fr, e) for fr, e in rows if fr.t >= 60.0]
    for name, truth in (('alpha_rad', lambda fr: fr.alpha), ('beta_rad', lambda fr: fr.beta),
                        ('mach', lambda fr: fr.mach)):
        z = np.array([(e.get(name) - truth(fr)) / e.sigma_of(name) for fr, e in late])
        assert np.max(np.abs(z)) < 4.5, name
        assert 0.3 < np.sqrt(np.mean(z**2)) < 1.6, name
    err = np.degrees([e.get('alpha_rad') - fr.alpha for fr, e in late])
    assert np.sqrt(np.mean(err**2)) < 0.07
    wind = np.array([e.wind_enu - np.array([5.0, -3.0, 0.0]) for _, e in late])
    sig = np.array([np.sqrt(np.diagonal(e.wind_cov)) for _, e in late])
    assert np.max(np.abs(wind / sig)) < 4.5


def test_a_blocked_port_is_excluded_and_the_filter_carries_on():
    """Port 1 (bottom) freezes at 60 s. A frozen port is only wrong once the flow has changed: it must be
    excluded within 2 s of its error first exceeding 4 sigma (80 Pa), and the angles stay good."""
    model = PortModel()
    frames = flight(duration_s=150.0, rho=0.5)
    frozen, t_bad = None, None
    for fr in frames:
        if fr.t >= 60.0:
            frozen = fr.pressures[1] if frozen is None else frozen
            clean = model.pressures(fr.alpha, fr.beta, fr.mach, fr.p_inf)[1]
            if t_bad is None and abs(frozen - clean) > 80.0:
                t_bad = fr.t
            fr.pressures[1] = frozen
    assert t_bad is not None
    f, rows = _run('ckf', frames, port_correlation=0.5)
    assert f.excluded_ports == (1,)
    t_detect = f.detector.detections[0][0]
    assert 60.0 <= t_detect <= t_bad + 2.0
    late = [(fr, e) for fr, e in rows if fr.t >= t_detect + 10.0]
    err = np.degrees([e.get('alpha_rad') - fr.alpha for fr, e in late])
    assert np.sqrt(np.mean(err**2)) < 0.1


def test_bad_frames_are_refused_and_counted():
    frames = flight(duration_s=5.0)
    f, _ = _run('ckf', frames)
    before = f.counts['updates']
    assert not f.push_frame(10.0, np.full(5, np.nan))
    assert not f.push_frame(10.0, np.full(4, 1e4))
    assert f.counts['not_finite'] == 2 and f.counts['updates'] == before
