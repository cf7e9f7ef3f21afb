"""What the engine publishes (docs/engine.md, outputs): the slave INS solution after the filter's
corrections as odometry (position, attitude and body velocity and rate, with covariances), and
the published view of the estimates: never a non-finite or absurd estimate, and from an ERROR on
the last good estimate (held), so no topic ever carries NaN or a wrong alignment at OK."""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from alignment_core.compiled import FLOAT64, as_float, as_float64, is_float64_vector, kernel
from alignment_core.estimation.health import ERROR, OK, all_finite, finite
from alignment_core.estimation.matching import LiveSolution, MatchResults
from alignment_core.estimation.models import ErrorModel
from alignment_core.estimation.models.base import DV, EPS
from alignment_core.estimation.outputs import Estimate
from alignment_core.estimation.state_estimate import StateEstimate
from alignment_core.geometry import earth
from alignment_core.geometry.rotations_compiled import quat_to_dcm_k
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import DEG, DPH

_NDARRAY = np.ndarray
UNKNOWN = -1.0            # a covariance diagonal of -1: not estimated (as /alignment/attitude's position)


class Odometry(NamedTuple):
    """The slave solution for /alignment/odom (world ENU position, body FLU axes)."""
    p_w: np.ndarray           # (3,) m
    v_b: np.ndarray           # (3,) m/s, velocity w.r.t. the Earth in body axes
    w_b: np.ndarray           # (3,) rad/s, body rate w.r.t. the nav frame
    pose_cov: np.ndarray      # (6, 6) position m^2, attitude rad^2 (nav-frame rotation vector)
    twist_cov: np.ndarray     # (6, 6) body velocity, body rate


class OdometryMaker:
    """Odometry of the slave from its NavState, the filter's covariance and the last gyro sample.
    Velocity covariance: the velocity error states (nav axes) rotated into body axes, unknown (-1)
    when a model lacks an axis; position: from seed001_13's dlat/dlon states, else unknown; body
    rate: the gyro's white noise over one IMU interval plus its bias uncertainty."""

    def __init__(self, model: ErrorModel, plane: earth.TangentPlane, imu_dt: float, arw_dpsh: float,
                 gyro_bias_sigma_dph: float) -> None:
        self._plane = plane
        n = len(model.kinds)
        self.attitude_states = np.arange(n)[model.attitude]          # (3,) indices
        if len(self.attitude_states) != 3:
            raise ValueError(f'the attitude states {model.attitude} of the model are not three')
        dv = [i for i, k in enumerate(model.kinds) if k == DV]
        self._dv = np.array(dv if len(dv) == 3 else [], dtype=np.int64)
        eps = [i for i, k in enumerate(model.kinds) if k == EPS]
        self._eps = np.array(eps if len(eps) == 3 else [], dtype=np.int64)
        labels = model.labels
        self._pos = (labels.index('dlon'), labels.index('dlat')) if 'dlat' in labels and 'dlon' in labels else None
        self._rate_var = (arw_dpsh * DEG / 60.0) ** 2 / imu_dt
        self._bias_var = (gyro_bias_sigma_dph * DPH) ** 2

    def make(self, st: NavState, p: np.ndarray, gyro: np.ndarray | None, bg: np.ndarray) -> Odometry:
        """p: the filter's covariance; gyro: the last raw gyro rate (None before the first IMU
        step), bg its bias estimate. The body rate w.r.t. the nav frame is the gyro's less the nav
        frame's own rate w.r.t. inertial space (Earth rate and transport rate at the solution)."""
        return self._make(st, p, gyro, bg)[0]

    def make_finite(self, st: NavState, p: np.ndarray, gyro: np.ndarray | None, bg: np.ndarray) -> Odometry | None:
        """`make`, or None when any of its numbers (position, velocity, rate, their covariances)
        is not finite."""
        odo, parts_finite = self._make(st, p, gyro, bg)
        if not parts_finite:
            return None
        if self._pos is not None and not finite(odo.pose_cov):
            return None
        return odo if finite(odo.p_w) else None

    def _make(self, st: NavState, p: np.ndarray, gyro: np.ndarray | None, bg: np.ndarray) -> tuple[Odometry, bool]:
        """(`make`, whether its velocity, rate and covariances before the position's are finite)."""
        v_e, v_n, _ = as_float64(st.v_n).tolist()
        w_in = np.array(earth.nav_rate_point(st.lat, st.h, v_e, v_n))
        p_w = self._plane.from_geodetic_point(st.lat, st.lon, st.h)
        w_m = w_in if gyro is None else gyro - bg
        p = as_float(p)
        v_b, w_b, pose, twist, parts_finite = odometry_parts(
            as_float64(st.q_nb), as_float64(st.v_n), as_float64(w_in), as_float64(w_m), gyro is not None, p,
            self.attitude_states, self._dv, self._eps, p.dtype.type(self._rate_var), self._rate_var + self._bias_var)
        if self._pos is not None:
            r_m, r_n = earth.radii(st.lat)
            i_lon, i_lat = self._pos
            pose[0, 0] = p[i_lon, i_lon] * (float(r_n) + st.h) ** 2 * math.cos(st.lat) ** 2
            pose[1, 1] = p[i_lat, i_lat] * (float(r_m) + st.h) ** 2
        return Odometry(p_w, v_b, w_b, pose, twist), parts_finite


class EstimateMaker:
    """The Estimate of each output instant from the live solution and the matches' results; after
    a breakdown, the last healthy output's covariance, sigma, diagnostics and odometry covariances
    (held) with the free-inertial slave's attitude and odometry."""

    def __init__(self, model: ErrorModel, odometry: OdometryMaker) -> None:
        self._model = model
        self._odometry = odometry
        self._p_shape = (model.n, model.n)          # covariance_parts' P
        self.state = StateEstimate(model.labels)
        self.held_state: np.ndarray | None = None      # the accumulated estimate at the last keep
        self.held: tuple[np.ndarray, np.ndarray, dict, np.ndarray, np.ndarray] | None = None

    def keep(self, live: LiveSolution, res: MatchResults) -> Odometry | None:
        """Keep the live covariance for the next output (and as the held one) and return the live
        odometry (for `make` at the same instant); None if the covariance, the published
        misalignment or the odometry (position, velocity, rate, their covariances) is not finite:
        a non-finite output is a breakdown (docs/engine.md), never an output at OK."""
        p = live.kf.P
        mu, mu_sigma = res.mu, res.mu_sigma
        ok = False
        if type(p) is _NDARRAY and p.dtype.char in 'fd' and p.shape == self._p_shape and is_float64_vector(mu) \
                and is_float64_vector(mu_sigma):
            cov, sigma, ok = covariance_parts(p, self._odometry.attitude_states, mu, mu_sigma)
        if not ok:                  # numpy's lines decide (and warn, or raise under np.errstate, as they do)
            att = self._model.attitude
            cov, sigma = p[att, att].copy(), np.sqrt(np.diag(p))
            if not (finite(cov, sigma) and finite(mu, mu_sigma)):
                return None
        odo = self._odometry.make_finite(live.ins.s, p, live.gyro, res.corr.bg)
        if odo is None:
            return None
        self.held = (cov, sigma, live.kf.diagnostics(), odo.pose_cov, odo.twist_cov)
        self.held_state = self.state.values(live.kf.x, res.corr)
        return odo

    def make(self, t: int, live: LiveSolution, res: MatchResults, updates: int, matching: bool,
             level: int, flags: tuple[str, ...], t_valid: int | None = None,
             odometry: Odometry | None = None) -> Estimate:
        """The output at master stamp t, valid at t_valid (default t), with what `keep` kept
        last (the prior before any); `odometry`: what `keep` just returned for this same live
        state (saves computing it twice), else computed here."""
        st = live.ins.s
        if self.held is None:
            att, p0 = self._model.attitude, self._model.initial_covariance()
            odo0 = self._odometry.make(st, p0, live.gyro, res.corr.bg)
            self.held = (p0[att, att].copy(), np.sqrt(np.diag(p0)), {}, odo0.pose_cov, odo0.twist_cov)
        cov, sigma, diag, pose_cov, twist_cov = self.held
        if odometry is None:
            odometry = self._odometry.make(st, live.kf.P, live.gyro, res.corr.bg)
        p_w, v_b, w_b = odometry[:3]
        corr = res.corr
        return Estimate(
            t_ns=t, misalignment=res.mu.copy(), misalignment_sigma=res.mu_sigma.copy(),
            q_nb=st.q_nb.copy(), attitude_cov=cov, x=res.x.copy(),
            sigma=sigma, bias_gyro=corr.bg.copy(), bias_accel=corr.ba.copy(),
            nis=res.nis, updates=updates, matching=matching, fading=diag.get('fading', 1.0),
            healthy=level < ERROR, level=level, flags=flags, p_w=p_w, v_b=v_b, w_b=w_b,
            pose_cov=pose_cov, twist_cov=twist_cov,
            state=None if self.held_state is None else self.held_state.copy(),
            t_valid_ns=t if t_valid is None else t_valid, t_nav_ns=live.t_ns)


class PublishGuard:
    """The published view: an estimate at level ERROR, or with a non-finite field, or a
    misalignment or a misalignment sigma beyond `max_misalignment` rad (a filter that claims to
    know less than that knows nothing a small-angle model can use), is replaced by the last good
    one (the last at OK, since a WARN may already be the start of the trouble; stamped now, at
    ERROR, flagged 'held');
    before any good one, by the prior (zero misalignment, its sigma).
    After a numerical breakdown the engine holds its last good estimate itself (the outputs
    carry it, with the free-inertial attitude): those pass, flagged 'held', unless the view is
    already holding an earlier one."""

    def __init__(self, max_misalignment: float) -> None:
        self.max_misalignment = max_misalignment
        self.last_good: Estimate | None = None
        self.holding = False

    def good(self, e: Estimate) -> bool:
        """Finite, a unit attitude quaternion, the misalignment and its sigma within the bound; an
        estimate of float64 arrays (the misalignment, its sigma and the quaternion vectors) under a
        float bound is first offered to one compiled check that says yes only where these rules
        surely do (`surely_good`)."""
        arrays = (e.misalignment, e.misalignment_sigma, e.q_nb, e.attitude_cov, e.x, e.sigma, e.p_w, e.v_b, e.w_b,
                  e.pose_cov, e.twist_cov, e.state)
        if type(self.max_misalignment) is float and all(
                type(a) is _NDARRAY and a.dtype == FLOAT64 and a.ndim >= 1 for a in arrays) and \
                arrays[0].ndim == arrays[1].ndim == arrays[2].ndim == 1 and \
                surely_good(*arrays, self.max_misalignment):
            return True
        return self._good_by_rules(e)

    def _good_by_rules(self, e: Estimate) -> bool:
        arrays = [e.misalignment, e.misalignment_sigma, e.q_nb, e.attitude_cov, e.x, e.sigma]
        arrays += [a for a in (e.p_w, e.v_b, e.w_b, e.pose_cov, e.twist_cov, e.state) if a is not None]
        if not finite(*arrays):
            return False
        q = e.q_nb
        if abs(float(q @ q) - 1.0) > 1e-6:
            return False
        bound = self.max_misalignment       # maxima of Python floats: numpy's cost microseconds on 3-vectors
        return max(map(abs, e.misalignment.tolist())) <= bound and max(e.misalignment_sigma.tolist()) <= bound

    def publish(self, e: Estimate, prior: Callable[[Estimate], Estimate]) -> Estimate:
        """What a node publishes for output e; prior(e) stands in before the first good one."""
        good = self.good(e)
        if good and e.level < ERROR:
            if e.level == OK or self.last_good is None:
                self.last_good = e
            self.holding = False
            return e
        if good and not self.holding and set(e.flags) == {'breakdown'}:
            return dataclasses.replace(e, flags=(*e.flags, 'held'))
        self.holding = True
        held = self.last_good if self.last_good is not None else prior(e)
        why = e.flags if good else (*e.flags, 'absurd')
        return dataclasses.replace(held, t_ns=e.t_ns, t_valid_ns=e.t_valid_ns, t_nav_ns=e.t_nav_ns, level=ERROR,
                                   healthy=False,
                                   matching=False,
                                   updates=e.updates, flags=tuple(dict.fromkeys((*why, 'held'))), report=e.report)


def prior_estimate(e: Estimate, mu_sigma: np.ndarray, p0: np.ndarray, att: slice) -> Estimate:
    """The stand-in before any good estimate: zero misalignment with the prior's sigma and
    covariance, e's attitude if it is a finite unit quaternion (else the identity), no odometry."""
    q = e.q_nb if finite(e.q_nb) and abs(float(e.q_nb @ e.q_nb) - 1.0) <= 1e-6 else np.array([0.0, 0.0, 0.0, 1.0])
    return dataclasses.replace(
        e, misalignment=np.zeros(3), misalignment_sigma=mu_sigma.copy(), q_nb=q, attitude_cov=p0[att, att].copy(),
        x=np.zeros(len(e.x)), sigma=np.sqrt(np.diag(p0)), bias_gyro=np.zeros(3), bias_accel=np.zeros(3),
        nis=math.nan, p_w=None, v_b=None, w_b=None, pose_cov=None, twist_cov=None, state=np.zeros(len(e.x)))


@kernel
def covariance_parts(p, att, mu, mu_sigma):
    """(the attitude block P[att, att] (3, 3), sqrt(diag P) (n,), and whether both and the
    misalignment mu and its sigma (float64 vectors) are all finite) of a covariance p (n, n),
    float64 or float32, att the attitude states (3,): EstimateMaker.keep's numpy lines in one
    call, the same numbers (a copy, and square roots in p's precision)."""
    n = p.shape[0]
    cov = np.empty((3, 3), p.dtype)
    sigma = np.empty(n, p.dtype)
    ok = True
    for i in range(3):
        for j in range(3):
            v = p[att[i], att[j]]
            cov[i, j] = v
            ok = ok and -math.inf < v < math.inf
    for i in range(n):
        v = np.sqrt(p[i, i])
        sigma[i] = v
        ok = ok and -math.inf < v < math.inf
    for i in range(mu.shape[0]):
        ok = ok and -math.inf < mu[i] < math.inf
    for i in range(mu_sigma.shape[0]):
        ok = ok and -math.inf < mu_sigma[i] < math.inf
    return cov, sigma, ok


@kernel
def surely_good(mu, mu_sigma, q, att_cov, x, sigma, p_w, v_b, w_b, pose, twist, state, bound):
    """True only where PublishGuard's rules surely call an estimate of float64 arrays good (every
    number finite, |q . q - 1| <= 1e-6, |mu| and mu_sigma within bound). q . q is summed here in
    order, which may differ from numpy's BLAS dot in the last bits, so a norm within 1e-12 of the
    tolerance is left to the rules (False), as is anything they reject."""
    if not (all_finite(mu) and all_finite(mu_sigma) and all_finite(q) and all_finite(att_cov) and all_finite(x)
            and all_finite(sigma) and all_finite(p_w) and all_finite(v_b) and all_finite(w_b)
            and all_finite(pose) and all_finite(twist) and all_finite(state)):
        return False
    if q.shape[0] != 4 or mu.shape[0] == 0 or mu_sigma.shape[0] == 0:      # the rules' max() raises on empty
        return False
    qq = 0.0
    for v in q:
        if v != 0.0 and abs(v) < 1e-150:        # its square underflows: numpy's product may raise (errstate)
            return False
        qq += v * v
    if not abs(qq - 1.0) <= 1e-6 - 1e-12:
        return False
    for v in mu:
        if not abs(v) <= bound:
            return False
    for v in mu_sigma:
        if not v <= bound:
            return False
    return True


@kernel
def odometry_parts(q_nb, v_n, w_in, w_m, has_rate, p, att, dv, eps, rate_var, rate_bias_var):
    """(v_b, w_b (3,), pose_cov, twist_cov (6, 6), whether all four are finite) of
    OdometryMaker.make: q_nb (4,), v_n, the nav
    frame's rate w_in and the measured rate w_m = gyro - bias (3,); has_rate False: w_b is zero;
    p (n, n) the filter's covariance (float64 or float32); att, dv, eps: the indices (3,) of the
    attitude, velocity and gyro bias states (dv, eps empty: the model lacks them, velocity
    unknown, the bias variance given); rate_var the gyro noise's variance in p's dtype (the sum
    with a bias variance is taken in it, as numpy adds a float to a float32 array),
    rate_bias_var its sum with the given bias variance. Position: unknown (the caller fills it).
    The products are numpy's: C^T v and C^T P_v C through the same BLAS calls."""
    c = np.array(quat_to_dcm_k((q_nb[0], q_nb[1], q_nb[2], q_nb[3]))).reshape(3, 3)
    ct = c.T
    v_b = np.dot(ct, v_n)
    w_b = w_m - np.dot(ct, w_in) if has_rate else np.zeros(3)
    pose = np.zeros((6, 6))
    twist = np.zeros((6, 6))
    pv = np.empty((3, 3))
    for i in range(3):
        pose[i, i] = UNKNOWN
        for j in range(3):
            pose[3 + i, 3 + j] = p[att[i], att[j]]
            if dv.shape[0] == 3:
                pv[i, j] = p[dv[i], dv[j]]
    if dv.shape[0] == 3:
        twist[:3, :3] = np.dot(np.dot(ct, pv), c)
    for i in range(3):
        if dv.shape[0] != 3:
            twist[i, i] = UNKNOWN
        twist[3 + i, 3 + i] = rate_var + p[eps[i], eps[i]] if eps.shape[0] == 3 else rate_bias_var
    ok = True
    for i in range(3):
        ok = ok and -math.inf < v_b[i] < math.inf and -math.inf < w_b[i] < math.inf
    for i in range(6):
        for j in range(6):
            ok = ok and -math.inf < pose[i, j] < math.inf and -math.inf < twist[i, j] < math.inf
    return v_b, w_b, pose, twist, ok
