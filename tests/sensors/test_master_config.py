"""The 'schuler' master INS checked at load against the ship's latitude: the gyrocompass loop's
latitude limit (error_dynamics' own test, which raised during the simulation) and the largest
`aligned_ago_s` whose noise covariance the Van Loan discretisation computes (beyond it: wrong,
then LinAlgError at construction); and a message's prefix given once."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov

from alignment_core.config import scenario
from alignment_core.sensors.master_ins import VAN_LOAN_MAX_EXPONENT, MasterInsModel, discretise, error_dynamics
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


def test_an_aligned_age_beyond_the_discretisations_reach_is_refused():
    """Two weeks (the sweep's case) raised LinAlgError 'Eigenvalues did not converge'."""
    with pytest.raises(ConfigError, match=r"^master\.aligned_ago_s = 1\.2096e\+06 s is beyond 27860 s, the "
                                          r"largest age allowed with damping_ratio 0\.5 and gyrocompass_tau_s 3600 s "
                                          r"at 40 deg: the noise covariance's discretisation grows as "
                                          r"exp\(t / 1548 s\)"):
        scenario.load('catapult_paper', {**NOISY_ALIGNED, 'master.aligned_ago_s': 1209600.0})
    with pytest.raises(ConfigError, match=r"is beyond (\d+) s, the largest age allowed with damping_ratio 2 "):
        scenario.load('catapult_paper', {**NOISY_ALIGNED, 'master.aligned_ago_s': 86400.0,
                                         'master.damping_ratio': 2.0})


def test_noise_free_or_free_masters_keep_any_age():
    """No noise: no covariance is drawn from; no damping: exp(-F t) does not grow."""
    old = {'master.aligned_ago_s': 1209600.0}
    assert scenario.load('catapult_paper', {**SCHULER, 'master.initial': 'aligned', **old}).master.aligned_ago_s > 0
    assert scenario.load('catapult_paper', {**NOISY_ALIGNED, 'master.damping': 'none', **old}).master.model == 'schuler'


@pytest.mark.parametrize('lat,zeta,tau', [(40.0, 0.5, 3600.0), (0.0, 1.0, 3600.0), (70.0, 0.1, 1e6)])
def test_the_largest_age_allowed_still_gives_the_covariance(lat, zeta, tau):
    """At the limit the Van Loan Qd is P_inf - Phi P_inf Phi^T (the stable form) to 1e-3 of its
    diagonal, and the model builds; just beyond, the load refuses."""
    age = np.floor(_limit(lat, zeta, tau))
    keys = {**NOISY_ALIGNED, 'ship.lat_deg': lat, 'master.damping_ratio': zeta, 'master.gyrocompass_tau_s': tau}
    sc = scenario.load('catapult_paper', {**keys, 'master.aligned_ago_s': float(age)})
    with pytest.raises(ConfigError, match='the largest age allowed'):
        scenario.load('catapult_paper', {**keys, 'master.aligned_ago_s': float(age + 2.0)})
    model = MasterInsModel(sc.master, sc.seed, lat * DEG, sc.t0_ns).schuler
    assert model is not None and np.all(np.isfinite(model.x))
    phi, _, qd = discretise(model.f, model.b, model.qc, age)
    p_inf = solve_continuous_lyapunov(model.f, -model.qc)
    stable = p_inf - phi @ p_inf @ phi.T
    scale = np.sqrt(np.outer(np.diag(stable), np.diag(stable)))
    assert np.max(np.abs(qd - stable) / scale) < 1e-3


def test_the_settled_state_message_names_its_section_once():
    with pytest.raises(ConfigError, match=r"^master: initial: 'settled' needs damping 'velocity' \(a free INS has no "
                                          r"steady state\); use initial: aligned$"):
        scenario.load('catapult_paper', {**SCHULER, 'master.damping': 'none'})
