"""The 'schuler' master INS checked at load against the ship's latitude: the gyrocompass loop's
latitude limit (error_dynamics' own test, which raised during the simulation); an `aligned_ago_s`
of any length (Van Loan's covariance lost its precision, then raised LinAlgError, beyond a few
hours: the stable form takes over); and a message's prefix given once."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov

from alignment_core.config import scenario
from alignment_core.sensors.master_ins import (
    VAN_LOAN_MAX_EXPONENT,
    MasterInsModel,
    aligned_since,
    discretise,
    error_dynamics,
)
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

SCHULER = {'master.model': 'schuler'}
NOISY_ALIGNED = {**SCHULER, 'master.initial': 'aligned', 'master.arw_dpsh': 0.001, 'master.vrw_ugpshz': 10.0}


@pytest.mark.parametrize('lat', [78.5, -80.0, 89.0])
def test_a_gyrocompassing_master_beyond_its_latitude_is_refused(lat):
    with pytest.raises(ConfigError, match=rf"^ship\.lat_deg = {lat} is out of range for master\.model schuler "
                                          rf"with damping velocity: a gyrocompassing master INS needs "
                                          rf"\|latitude\| < 78 deg"):
        scenario.load('catapult_paper', {**SCHULER, 'ship.lat_deg': lat})


@pytest.mark.parametrize('lat', [75.0, 78.4, 78.5, 80.0])
def test_the_latitude_verdict_is_the_models(lat):
    """Loads exactly where error_dynamics has its loop; the free INS and 'constant' load anywhere."""
    try:
        error_dynamics(lat * DEG)
        works = True
    except ValueError:
        works = False
    try:
        scenario.load('catapult_paper', {**SCHULER, 'ship.lat_deg': lat})
        loads = True
    except ConfigError:
        loads = False
    assert loads == works
    free = {**SCHULER, 'master.damping': 'none', 'master.initial': 'aligned', 'ship.lat_deg': lat}
    assert scenario.load('catapult_paper', free).ship.lat_deg == lat
    assert scenario.load('catapult_paper', {'ship.lat_deg': lat}).master.model == 'constant'


def _limit(lat_deg: float = 40.0, zeta: float = 0.5, tau_s: float = 3600.0) -> float:
    f, _ = error_dynamics(lat_deg * DEG, 'velocity', zeta, tau_s)
    return VAN_LOAN_MAX_EXPONENT / float(np.max(-np.linalg.eigvals(f).real))


def test_a_master_aligned_long_ago_starts_from_the_settled_covariance():
    """Two weeks (the sweep's case: LinAlgError 'Eigenvalues did not converge' at construction)
    loads and builds; its covariance is the settled one, the Lyapunov solution (the loop's slowest
    mode has decayed by exp(-750) by then), to rounding."""
    sc = scenario.load('catapult_paper', {**NOISY_ALIGNED, 'master.aligned_ago_s': 1209600.0})
    model = MasterInsModel(sc.master, sc.seed, 40.0 * DEG, sc.t0_ns).schuler
    assert model is not None and np.all(np.isfinite(model.x))
    _, _, p = aligned_since(model.f, model.b, model.qc, 1209600.0)
    p_inf = solve_continuous_lyapunov(model.f, -model.qc)
    scale = np.sqrt(np.outer(np.diag(p_inf), np.diag(p_inf)))
    assert np.max(np.abs(p - p_inf) / scale) < 1e-9


def test_noise_free_or_free_masters_keep_any_age():
    """No noise: no covariance is drawn from; no damping: exp(-F t) does not grow."""
    old = {'master.aligned_ago_s': 1209600.0}
    assert scenario.load('catapult_paper', {**SCHULER, 'master.initial': 'aligned', **old}).master.aligned_ago_s > 0
    assert scenario.load('catapult_paper', {**NOISY_ALIGNED, 'master.damping': 'none', **old}).master.model == 'schuler'


@pytest.mark.parametrize('lat,zeta,tau', [(40.0, 0.5, 3600.0), (0.0, 1.0, 3600.0), (70.0, 0.1, 1e6)])
def test_the_covariance_is_continuous_where_van_loan_hands_over_to_the_stable_form(lat, zeta, tau):
    """Just inside VAN_LOAN_MAX_EXPONENT the Van Loan Qd, just beyond it P_inf - Phi P_inf Phi^T:
    the same covariance to 1e-3 of its diagonal (Van Loan has lost ~8 digits there, the stable
    form none), and a master aligned that long ago builds either side."""
    age = _limit(lat, zeta, tau)
    f, b = error_dynamics(lat * DEG, 'velocity', zeta, tau)
    qc = np.diag([(0.001 * DEG / 60.0) ** 2] * 3 + [(10.0 * 9.80665e-6) ** 2] * 2)
    _, _, before = aligned_since(f, b, qc, age * (1.0 - 1e-6))
    _, _, after = aligned_since(f, b, qc, age * (1.0 + 1e-6))
    assert np.array_equal(before, discretise(f, b, qc, age * (1.0 - 1e-6))[2])
    scale = np.sqrt(np.outer(np.diag(after), np.diag(after)))
    assert np.max(np.abs(before - after) / scale) < 1e-3
    keys = {**NOISY_ALIGNED, 'ship.lat_deg': lat, 'master.damping_ratio': zeta, 'master.gyrocompass_tau_s': tau}
    for t in (np.floor(age), np.ceil(age) + 2.0):
        sc = scenario.load('catapult_paper', {**keys, 'master.aligned_ago_s': float(t)})
        model = MasterInsModel(sc.master, sc.seed, lat * DEG, sc.t0_ns).schuler
        assert model is not None and np.all(np.isfinite(model.x))


def test_the_settled_state_message_names_its_section_once():
    with pytest.raises(ConfigError, match=r"^master: initial: 'settled' needs damping 'velocity' \(a free INS has no "
                                          r"steady state\); use initial: aligned$"):
        scenario.load('catapult_paper', {**SCHULER, 'master.damping': 'none'})
