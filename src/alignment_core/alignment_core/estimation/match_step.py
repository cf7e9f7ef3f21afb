"""One master match of velocity matching (vm12, vm15), with or without the delay and lever-arm
states appended, under the plain Kalman filter, compiled whole: the measurement matrix with the
layers' columns, a beam LDV's projection, H Phi^-1 for a match in the slave's past, the Kalman
update, the health check, the feedback (the lever arm's too), the slave's attitude at the
validity time carried by it, and the misalignment against the master brought forward by the
estimated delay, in one kernel: the same operations in the same order as the calls
Matcher.update_master makes otherwise (models/velocity_matching.py, lever_arm.py,
master_delay.py, beam.py, filters/kalman_kernels.py, health.py, matching.Matcher._carry).

Why: those calls cost several times their arithmetic from Python (docs/speed.md)."""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from alignment_core.compiled import FLOAT64, as_float64, kernel
from alignment_core.estimation.filters.base import UpdateResult
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.filters.kalman_kernels import update
from alignment_core.estimation.health import UNHEALTHY, NumericalBreakdownError, healthy
from alignment_core.estimation.models.base import Corrections, ErrorModel
from alignment_core.estimation.models.lever_arm import LeverArmStates
from alignment_core.estimation.models.master_delay import MasterDelayState
from alignment_core.estimation.models.velocity_matching import (
    VelocityMatching,
    feedback_k,
    measurement_k,
    misalignment_k,
)
from alignment_core.geometry.rotations_compiled import quat_mul_k, rotvec_to_dcm_k
from alignment_core.navigation.history import SlaveSnapshot
from alignment_core.navigation.history_kernels import carried_k, slave_between_k
from alignment_core.navigation.strapdown import NavState

_INF = float('inf')
_DECLINED = -1.0                 # _match's nis where it did nothing (a NIS is never negative)
_NONE1 = np.empty(0)             # an absent vector or matrix, as the kernel takes it
_NONE2 = np.empty((0, 0))
_NDARRAY = np.ndarray


class Layers(NamedTuple):
    """Where a velocity-matching model keeps its states: nb, velocity matching's own (12 or 15),
    the delay state's column and the lever-arm states' first (-1: not appended)."""
    nb: int
    delay: int = -1
    lever: int = -1


def layers_of(model: ErrorModel) -> Layers | None:
    """The layers of a model the kernel computes: VelocityMatching itself under at most one
    MasterDelayState and one LeverArmStates (those classes exactly: a subclass may compute its
    rows its own way); None for any other model."""
    delay = lever = -1
    while type(model) in (MasterDelayState, LeverArmStates):
        assert isinstance(model, (MasterDelayState, LeverArmStates))
        if type(model) is MasterDelayState:
            if delay >= 0:
                return None
            delay = model.nb
        else:
            if lever >= 0:
                return None
            lever = model.nb
        model = model.base
    if type(model) is not VelocityMatching:
        return None
    return Layers(model.n, delay, lever)


class Fed(NamedTuple):
    """An accepted update fed back: the state before feedback, the one the filter keeps after
    it, the misalignment and its sigma (aircraft axes, rad), and the slave's attitude at the
    match's validity time after the feedback (4,); for a match inside the slave's last step, the
    stored solution it started from with its attitude (4,) and velocity (3,) carried by the
    feedback (SlaveHistory.correct's), else None."""
    x: np.ndarray
    x_kept: np.ndarray
    mu: np.ndarray
    mu_sigma: np.ndarray
    q_valid: np.ndarray
    carried: tuple[SlaveSnapshot, np.ndarray, np.ndarray] | None = None


def _matrix(a: np.ndarray) -> np.ndarray:
    """a as a C-ordered float64 array (no copy when it is one)."""
    return a if type(a) is _NDARRAY and (a.dtype is FLOAT64 or a.dtype == FLOAT64) and a.flags.c_contiguous \
        else np.ascontiguousarray(a, dtype=np.float64)


def update_and_feed_back(kf: KalmanFilter, layers: Layers, z: np.ndarray, u_n: np.ndarray, r: np.ndarray,
                         gate: float | None, nav: NavState, corr: Corrections, c_m: np.ndarray,
                         c_nom: np.ndarray | None = None, w_m: np.ndarray | None = None,
                         a_n: np.ndarray | None = None, w_n: np.ndarray | None = None,
                         beam_n: np.ndarray | None = None, q_past: np.ndarray | None = None,
                         phi_acc: np.ndarray | None = None, step: tuple[SlaveSnapshot, float] | None = None
                         ) -> tuple[UpdateResult | None, Fed | None]:
    """kf.update with velocity matching's measurement (z = z_vel, u_n the lever-arm and deck
    velocity, nav frame, r (3, 3)) and the layers' columns (the delay's a_n, the lever arm's
    C_m [w_m x] with the master attitude c_m (3, 3) and body rate w_m), projected on a beam LDV's
    line of sight beam_n (nav frame), times Phi^-1 (phi_acc, from the validity time to now), then
    check_health; if accepted, the model's feedback into the live solution nav and corr (q_nb,
    v_n, bg, ba, dr replaced), the attitude q_past of the slave at the validity time carried by
    it (None: the match is at the live solution's time), and the misalignment against
    exp([w_n dt x]) c_m c_nom. step (a, f): the match is a fraction f into the slave's step from
    the stored solution a (its phi set) to the live one, nav: the kernel interpolates the solution
    there (history.Past.state's), z is given as v_ref (the innovation is that solution's velocity
    less it), q_past and phi_acc are None, and the feedback also carries a; (None, None), nothing
    done, where numpy's subtraction of v_ref would have warned (an overflow, inf - inf: the
    caller then takes that subtraction as it was). Raises as those calls raise (a singular Phi:
    np.linalg.LinAlgError, as the update with the non-finite H numpy's solve gives)."""
    x, p, y, s = kf.arrays_to_update(3 if beam_n is None else 1)
    carried = None
    try:
        if step is None:
            nis, accepted, ok, x_before, q, v, bg, ba, dr, x_kept, mu, sigma, q_valid = _match(
                x, p, y, s, as_float64(z), as_float64(u_n), as_float64(r), _INF if gate is None else gate, layers.nb,
                layers.delay, layers.lever, _matrix(c_m), _NONE2 if c_nom is None else _matrix(c_nom),
                _NONE1 if w_m is None else as_float64(w_m), _NONE1 if a_n is None else as_float64(a_n),
                _NONE1 if w_n is None else as_float64(w_n), _NONE1 if beam_n is None else as_float64(beam_n),
                _NONE2 if phi_acc is None else _matrix(phi_acc), as_float64(nav.q_nb), as_float64(nav.v_n),
                as_float64(corr.bg), as_float64(corr.ba), as_float64(corr.dr),
                _NONE1 if q_past is None else as_float64(q_past))
        else:
            a, f = step
            assert a.phi is not None
            nis, accepted, ok, x_before, q, v, bg, ba, dr, x_kept, mu, sigma, q_valid, q_a, v_a = _match_in_step(
                x, p, y, s, as_float64(z), as_float64(u_n), as_float64(r), _INF if gate is None else gate, layers.nb,
                layers.delay, layers.lever, _matrix(c_m), _NONE2 if c_nom is None else _matrix(c_nom),
                _NONE1 if w_m is None else as_float64(w_m), _NONE1 if a_n is None else as_float64(a_n),
                _NONE1 if w_n is None else as_float64(w_n), _NONE1 if beam_n is None else as_float64(beam_n),
                _matrix(a.phi), as_float64(nav.q_nb), as_float64(nav.v_n), as_float64(corr.bg), as_float64(corr.ba),
                as_float64(corr.dr), as_float64(a.q_nb), as_float64(a.v_n), f)
            if q_a is not None:
                carried = (a, q_a, v_a)
    except np.linalg.LinAlgError:           # S or Phi singular
        nis, accepted, ok = math.nan, False, True
    if nis == _DECLINED:
        return None, None
    upd = kf.account(y, s, nis, accepted)
    if not ok:
        raise NumericalBreakdownError(UNHEALTHY)
    if not accepted:
        return upd, None
    nav.q_nb, nav.v_n, corr.bg, corr.ba = q, v, bg, ba
    if dr is not None:
        corr.dr = dr
    return upd, Fed(x_before, x_kept, mu, sigma, q if q_valid is None else q_valid, carried)


@kernel
def _measurement(z, u_n, r, nb, n, delay, lever, c_m, w_m, a_n, beam_n, phi_acc):
    """(z, H (rows, n), R): velocity matching's H of nb states widened to n columns, the
    delay's column a_n and the lever arm's columns C_m [w_m x] (models/master_delay.py,
    lever_arm.py), projected on the beam (models/beam.py: one row), times Phi^-1."""
    h = measurement_k(u_n, n if nb == 15 else nb)     # vm15's cells fill n columns; vm12's H is widened
    if nb == 12 and n > 12:
        wide = np.zeros((3, n))
        wide[:, :12] = h
        h = wide
    if delay >= 0 and a_n.shape[0] == 3:
        h[0, delay], h[1, delay], h[2, delay] = a_n[0], a_n[1], a_n[2]
    if lever >= 0:
        wx, wy, wz = w_m[0], w_m[1], w_m[2]
        h[:, lever:lever + 3] = np.dot(c_m, np.array(((0.0, -wz, wy), (wz, 0.0, -wx), (-wy, wx, 0.0))))
    zz, hh, rr = z, h, r
    if beam_n.shape[0] == 3:
        pm = np.zeros((1, 3))
        pm[0, :] = beam_n
        zz = np.array([np.dot(beam_n, z)])        # numpy's (1, 3) @ (3,) is this dot
        hh = np.dot(pm, h)
        rr = np.dot(np.dot(pm, r), pm.T)
    if phi_acc.shape[0] > 0:
        hh = np.ascontiguousarray(np.linalg.solve(phi_acc.T, hh.T).T)
    return zz, hh, rr


@kernel
def _match(x, p, y, s, z, u_n, r, gate, nb, delay, lever, c_m, c_nom, w_m, a_n, w_n, beam_n, phi_acc,
           q_nb, v_n, bg, ba, dr, q_past):
    """The update (x, P, y, S in place) with _measurement's z, H, R; (nis, accepted, healthy,
    then, if both, x before feedback, q_nb, v_n, bg, ba, dr (None without lever-arm states), the
    state kept after it, mu, sigma and the slave's attitude at the validity time (None for a
    match at the live solution's time); else Nones: a None costs nothing to hand back, an array
    about 0.15 us: compiled_boxing.py)."""
    zz, hh, rr = _measurement(z, u_n, r, nb, x.shape[0], delay, lever, c_m, w_m, a_n, beam_n, phi_acc)
    nis, accepted = update(x, p, zz, hh, rr, gate, y, s)
    ok = healthy(x, p)
    if not (accepted and ok):
        return nis, accepted, ok, None, None, None, None, None, None, None, None, None, None
    x_before = x.copy()
    q, v, bg1, ba1, x_kept = feedback_k(q_nb, v_n, bg, ba, x)
    dr1 = None                                # unchanged
    if lever >= 0:
        dr1 = dr + x[lever:lever + 3]
        x_kept[lever:lever + 3] = 0.0
    q_at, q_valid = q, None                   # at the live solution's time: q
    if q_past.shape[0] == 4:                  # Matcher._carry: the live correction applied there
        q_corr = quat_mul_k((q[0], q[1], q[2], q[3]), (-q_nb[0], -q_nb[1], -q_nb[2], q_nb[3]))
        qa = np.array(quat_mul_k(q_corr, (q_past[0], q_past[1], q_past[2], q_past[3])))
        q_at = qa / np.sqrt(np.dot(qa, qa))
        q_valid = q_at
    c_a = c_m
    if delay >= 0 and w_n.shape[0] == 3:      # the master brought forward by dt
        dt = x_kept[delay]
        c_a = np.dot(np.array(rotvec_to_dcm_k(w_n[0] * dt, w_n[1] * dt, w_n[2] * dt)).reshape(3, 3), c_m)
    if c_nom.shape[0] == 3:
        c_a = np.dot(c_a, c_nom)
    mu, sigma = misalignment_k(q_at, c_a, x_kept, p, nb == 15)
    return nis, accepted, ok, x_before, q, v, bg1, ba1, dr1, x_kept, mu, sigma, q_valid


@kernel
def _match_in_step(x, p, y, s, v_ref, u_n, r, gate, nb, delay, lever, c_m, c_nom, w_m, a_n, w_n, beam_n, phi_a,
                   q_nb, v_n, bg, ba, dr, q_a, v_a, f):
    """_match at a validity time a fraction f (0 < f < 1) into the step from the stored solution
    (q_a, v_a, its transition phi_a) to the live one (q_nb, v_n): the solution there
    (history.Past.state's), the innovation against v_ref, then _match's values and, if it fed
    back, the stored solution's attitude and velocity carried (SlaveHistory.correct's), else
    Nones; nis -1 and nothing done where numpy's z = v - v_ref would warn (overflow, inf - inf)."""
    q_past, v_past, cut = slave_between_k(q_a, q_nb, v_a, v_n, f, phi_a)
    z = v_past - v_ref
    for i in range(3):
        d, a, b = z[i], v_past[i], v_ref[i]
        if (math.isinf(d) and math.isfinite(a) and math.isfinite(b)) or (
                math.isnan(d) and not (math.isnan(a) or math.isnan(b))):
            return -1.0, False, True, None, None, None, None, None, None, None, None, None, None, None, None
    nis, accepted, ok, x_before, q, v, bg1, ba1, dr1, x_kept, mu, sigma, q_valid = _match(
        x, p, y, s, z, u_n, r, gate, nb, delay, lever, c_m, c_nom, w_m, a_n, w_n, beam_n, cut, q_nb, v_n, bg, ba, dr,
        q_past)
    if q is None or v is None:
        return nis, accepted, ok, x_before, q, v, bg1, ba1, dr1, x_kept, mu, sigma, q_valid, None, None
    q_c, v_c = carried_k(q_nb, q, v_n, v, q_a, v_a)
    return nis, accepted, ok, x_before, q, v, bg1, ba1, dr1, x_kept, mu, sigma, q_valid, q_c, v_c
