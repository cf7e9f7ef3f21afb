"""Time-of-validity bookkeeping for the alignment filter: a short history of the slave solution
and of the LDV stream, so that master data valid at t_v = stamp - latency are compared with the
slave solution and the deck velocity at that same t_v (sensors/timing.py stamps data valid at t
as t + latency).

Slave history: the strapdown solution at each IMU step before the latest one (the latest is the
engine's live state), each with the error-state transition Phi of the step that starts there.
Between two steps the solution is interpolated (attitude along the geodesic, velocity and
position linearly). Closed-loop feedback corrects the live state; `correct` applies the same
correction (a nav-frame rotation, a velocity and a position change) to the stored solutions,
so a later match against the past is not corrected twice. `transition_since(t_v)` is the
product of the Phi from t_v to the live state (a step cut by t_v contributes
I + f (Phi - I), f the fraction of the step after t_v): the engine's delay-aware measurement
matrix is H Phi^-1 (docs/engine.md).

LDV history: each sample by validity time, with the launch flag (`moving`) and the deck
displacement integrated up to it (trapezoids, as the engine integrates). At a time between
two samples: linear interpolation when both are valid (exact for the constant acceleration of
a catapult stroke; a change of acceleration inside the interval adds its bounded error to
the measurement noise), else (parked only) the valid neighbour within half the sample
spacing, else no measurement (LdvHistory).
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from alignment_core.compiled import FLOAT64, as_float64
from alignment_core.navigation.history_kernels import carried_k, ldv_between_k, slave_between_k
from alignment_core.navigation.strapdown import NavState

_NDARRAY = np.ndarray
_NO_PHI = np.empty((0, 0))
_NONE = np.empty(0)


@dataclass(slots=True)
class SlaveSnapshot:
    """The slave solution at t_ns and the transition of the step that starts there."""
    t_ns: int
    q_nb: np.ndarray
    v_n: np.ndarray
    lat: float
    lon: float
    h: float
    phi: np.ndarray | None = None

    def nav(self) -> NavState:
        return NavState(q_nb=self.q_nb, v_n=self.v_n, lat=self.lat, lon=self.lon, h=self.h)


class SlaveHistory:
    """The slave solutions of the last IMU steps (the live one excluded)."""

    def __init__(self, span_ns: int) -> None:
        self.span_ns = int(span_ns)
        self.items: deque[SlaveSnapshot] = deque()

    def record(self, t_ns: int, nav: NavState) -> SlaveSnapshot:
        """Store the live solution at t_ns before it is propagated; set its `phi` afterwards."""
        s = SlaveSnapshot(t_ns, nav.q_nb, nav.v_n, nav.lat, nav.lon, nav.h)
        self.items.append(s)
        return s

    def prune(self, keep_from_ns: int, t_live_ns: int) -> None:
        """Drop the snapshots no lookup at or after keep_from_ns needs (the last one before
        keep_from_ns stays: it brackets keep_from_ns with the next one, or with the live state)."""
        it = self.items
        while it and it[0].t_ns < keep_from_ns and (it[1].t_ns if len(it) > 1 else t_live_ns) <= keep_from_ns:
            it.popleft()

    def find(self, t_ns: int, live: NavState, t_live_ns: int, max_step_ns: int) -> Past | None:
        """Where t_ns falls (`Past`: the solution there is made when asked), or None when t_ns is
        older than the history, later than the live state, or inside a step longer than
        max_step_ns (an IMU gap: no interpolation across it)."""
        if t_ns == t_live_ns:
            return Past(self, -1, 0.0, live, (live, None))
        it = self.items
        if t_ns > t_live_ns or not it or t_ns < it[0].t_ns:
            return None
        k = len(it) - 1
        while it[k].t_ns > t_ns:
            k -= 1
        a_t = it[k].t_ns
        if t_ns == a_t:
            return Past(self, k, 0.0, live)
        b_t = it[k + 1].t_ns if k + 1 < len(it) else t_live_ns
        if b_t - a_t > max_step_ns:
            return None
        return Past(self, k, (t_ns - a_t) / (b_t - a_t), live)

    def state_at(self, t_ns: int, live: NavState, t_live_ns: int, max_step_ns: int
                 ) -> tuple[NavState, np.ndarray | None] | None:
        """(solution at t_ns, Phi from t_ns to the live state, None if not known), or None where
        `find` finds nothing."""
        past = self.find(t_ns, live, t_live_ns, max_step_ns)
        return None if past is None else past.state()

    def correct(self, q0: np.ndarray, q1: np.ndarray, v0: np.ndarray, v1: np.ndarray, dlat: float, dlon: float,
                dh: float, carried: tuple[SlaveSnapshot, np.ndarray, np.ndarray] | None = None) -> None:
        """Apply to every stored solution the feedback correction that took the live one from
        attitude q0 (4,) and velocity v0 (3,) to q1 and v1: the nav-frame rotation q1 q0^-1, the
        velocity change v1 - v0 and the position changes (one compiled call a solution).
        carried: (a stored solution, its q and v so corrected already: a compiled match's)."""
        if not self.items:
            return
        done = None if carried is None else carried[0]
        if len(self.items) > 1 or self.items[0] is not done:
            q0, q1, v0, v1 = as_float64(q0), as_float64(q1), as_float64(v0), as_float64(v1)
        for s in self.items:
            if s is done:
                assert carried is not None
                s.q_nb, s.v_n = carried[1], carried[2]
            else:
                s.q_nb, s.v_n = carried_k(q0, q1, v0, v1, as_float64(s.q_nb), as_float64(s.v_n))
            s.lat += dlat
            s.lon += dlon
            s.h += dh


class Past:
    """A validity time's place in the slave history (SlaveHistory.find): the live solution (k =
    -1), stored solution k (f = 0), or a fraction f of the step from stored solution k to the
    next (or the live one). `state` makes the solution there; a compiled match takes the step
    into the live one as it is (`into_live`) and interpolates it itself (estimation/match_step.py)."""
    __slots__ = ('history', 'k', 'f', 'live', '_state')

    def __init__(self, history: SlaveHistory, k: int, f: float, live: NavState,
                 state: tuple[NavState, np.ndarray | None] | None = None) -> None:
        self.history, self.k, self.f, self.live = history, k, f, live
        self._state = state

    def into_live(self) -> SlaveSnapshot | None:
        """The stored solution the time is inside the step of, when that step ends at the live
        solution and has its transition (float64 arrays): else None."""
        it = self.history.items
        if self.f == 0.0 or self.k != len(it) - 1:
            return None
        a = it[self.k]
        phi, q, v = a.phi, a.q_nb, a.v_n
        if type(phi) is _NDARRAY and phi.dtype == FLOAT64 and type(q) is _NDARRAY and q.dtype == FLOAT64 \
                and type(v) is _NDARRAY and v.dtype == FLOAT64:
            return a
        return None

    def state(self) -> tuple[NavState, np.ndarray | None]:
        """(the slave solution at the time, Phi from there to the live state, None if not known),
        made on the first call (the history as it is then) and kept."""
        if self._state is None:
            self._state = self._make_state()
        return self._state

    def _make_state(self) -> tuple[NavState, np.ndarray | None]:
        k, f, live = self.k, self.f, self.live
        if k < 0:
            return live, None
        it = self.history.items
        a = it[k]
        if f == 0.0:
            nav, phi_acc = a.nav(), a.phi
        else:
            b_q, b_v, b_pos = ((it[k + 1].q_nb, it[k + 1].v_n, (it[k + 1].lat, it[k + 1].lon, it[k + 1].h))
                               if k + 1 < len(it) else (live.q_nb, live.v_n, (live.lat, live.lon, live.h)))
            q, v, cut = slave_between_k(as_float64(a.q_nb), as_float64(b_q), as_float64(a.v_n), as_float64(b_v), f,
                                        _NO_PHI if a.phi is None else a.phi)
            nav = NavState(q_nb=q, v_n=v,
                           lat=a.lat + f * (b_pos[0] - a.lat), lon=a.lon + f * (b_pos[1] - a.lon),
                           h=a.h + f * (b_pos[2] - a.h))
            phi_acc = None if a.phi is None else cut
        if phi_acc is None:
            return nav, None
        for j in range(k + 1, len(it)):
            p = it[j].phi
            if p is None:
                return nav, None
            phi_acc = p @ phi_acc
        return nav, phi_acc


@dataclass(slots=True)
class LdvRecord:
    """The LDV at validity time t_ns: velocity (ship axes), validity, launch flag, the deck
    displacement integrated up to t_ns, and the variance (m/s)^2 per axis an interpolation
    adds (0 for a sample)."""
    t_ns: int
    v_s: np.ndarray
    valid: bool
    moving: bool
    disp: np.ndarray
    var: float = 0.0
    beam: np.ndarray | None = None      # a beam LDV's unit line of sight (ship axes)


def _beam_between(a: LdvRecord, b: LdvRecord, f: float) -> np.ndarray | None:
    """A beam LDV's line of sight at the fraction f between two samples (normalised linear
    interpolation; None for a vector LDV)."""
    if a.beam is None or b.beam is None:
        return None
    u = a.beam + f * (b.beam - a.beam)
    return u / math.sqrt(u.dot(u))          # np.linalg.norm's numbers without its wrapper


def _all_float64(r: LdvRecord) -> bool:
    """Every array of r a float64 numpy array (the compiled interpolation's operands)."""
    v, d, b = r.v_s, r.disp, r.beam
    return (type(v) is _NDARRAY and v.dtype == FLOAT64 and type(d) is _NDARRAY and d.dtype == FLOAT64
            and (b is None or (type(b) is _NDARRAY and b.dtype == FLOAT64)))


class LdvHistory:
    """LDV samples by validity time, looked up at a master's validity time (module docstring).

    Interpolation error: linear interpolation is exact while the acceleration is constant; a
    change of acceleration (the launch, the release) inside [a, b] makes v_b deviate from the
    extrapolation of the two samples before it by Delta = (k2 - k1)(1 - s) T (slopes k1, k2,
    the change at the fraction s), and the interpolation error at the fraction f is then at
    most |Delta| f. The part of Delta above three times its noise (sigma_ldv per sample) is
    taken as a 1-sigma error of |Delta| f and added to the measurement noise. While the
    aircraft moves, a time with only one valid neighbour gets no measurement (the nearest
    sample would be off by a dt: 0.4 m/s at 2 g and 20 ms); while parked (the velocity is not
    used, only the validity), the nearest valid sample within half the spacing counts."""

    def __init__(self, span_ns: int, sigma_mps: float) -> None:
        self.span_ns = int(span_ns)
        self.sigma2 = float(sigma_mps) ** 2
        self.items: deque[LdvRecord] = deque()
        self.spacing_ns = 0                 # between the last two samples
        self._float64 = True                # every sample recorded so far in float64: compiled interpolation

    def record(self, r: LdvRecord) -> None:
        if self._float64 and not _all_float64(r):
            self._float64 = False
        if self.items:
            self.spacing_ns = r.t_ns - self.items[-1].t_ns
        self.items.append(r)
        while len(self.items) > 3 and self.items[2].t_ns < r.t_ns - self.span_ns:
            self.items.popleft()

    @property
    def latest_ns(self) -> int | None:
        return self.items[-1].t_ns if self.items else None

    def at(self, t_ns: int) -> LdvRecord | None:
        """The LDV at t_ns (class docstring), or None before the history or after its end."""
        it = self.items
        if not it or t_ns < it[0].t_ns:
            return None
        last = it[-1]
        if t_ns >= last.t_ns:
            return last if t_ns == last.t_ns else None
        k = len(it) - 2
        while it[k].t_ns > t_ns:
            k -= 1
        a, b = it[k], it[k + 1]
        if t_ns == a.t_ns:
            return a
        span = b.t_ns - a.t_ns
        f = (t_ns - a.t_ns) / span
        if a.valid and b.valid:
            if self._float64:
                return self._between(k, a, b, t_ns, f)
            v = a.v_s + f * (b.v_s - a.v_s)
            disp = a.disp + 0.5 * (a.v_s + v) * ((t_ns - a.t_ns) * 1e-9) if b.moving else a.disp
            return LdvRecord(t_ns, v, True, b.moving, disp, self._kink_variance(k, f), _beam_between(a, b, f))
        if not (a.moving or b.moving):
            for near in ((a, b) if f <= 0.5 else (b, a)):
                if near.valid and abs(near.t_ns - t_ns) * 2 <= span:
                    return near
        return LdvRecord(t_ns, np.zeros(3), False, a.moving, a.disp)

    def _between(self, k: int, a: LdvRecord, b: LdvRecord, t_ns: int, f: float) -> LdvRecord:
        """The record the interpreted lines of `at` make between two valid samples, from one
        compiled call (history_kernels.py; every sample so far in float64)."""
        p = self.items[k - 1] if k > 0 else None
        v_p, rho, threshold = _NONE, 0.0, 0.0
        if p is not None and p.valid:
            v_p, rho = p.v_s, (b.t_ns - a.t_ns) / (a.t_ns - p.t_ns)
            threshold = self._kink_threshold(rho)
        beam = a.beam is not None and b.beam is not None
        v, disp, var, u = ldv_between_k(a.v_s, b.v_s, f, a.disp, (t_ns - a.t_ns) * 1e-9 if b.moving else -1.0,
                                        v_p, rho, threshold, a.beam if beam else _NONE, b.beam if beam else _NONE)
        return LdvRecord(t_ns, v, True, b.moving, disp if b.moving else a.disp, var, u if beam else None)

    def _kink_variance(self, k: int, f: float) -> float:
        """Interpolation error variance at the fraction f of [it[k], it[k+1]] (class docstring)."""
        if k == 0:
            return 0.0
        p, a, b = self.items[k - 1], self.items[k], self.items[k + 1]
        if not p.valid:
            return 0.0
        rho = (b.t_ns - a.t_ns) / (a.t_ns - p.t_ns)
        delta = b.v_s - (1.0 + rho) * a.v_s + rho * p.v_s
        excess = float(delta @ delta) - self._kink_threshold(rho)
        return excess * f * f if excess > 0.0 else 0.0

    def _kink_threshold(self, rho: float) -> float:
        """|Delta|^2 below which a kink is taken for noise: three sigma of Delta per axis, its
        variance sigma^2 (1 + (1 + rho)^2 + rho^2) from the three samples it is made of."""
        return 9.0 * 3.0 * (self.sigma2 * (1.0 + (1.0 + rho) ** 2 + rho ** 2))
