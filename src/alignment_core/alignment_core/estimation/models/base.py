"""The interface every error-state model offers the transfer-alignment engine.

The engine (estimation/engine.py, docs/engine.md) owns the slave strapdown, the sensor-bias estimates, the
lever arm and the matching reference; a model owns the error state: its labels, how it
propagates, what it measures and how an estimate is fed back. Per IMU interval the engine
calls `transition(p)` / `process_noise(h)` (or, for a nonlinear model, `propagator(p)`); per
matching instant `measurement(m, corr)`, then `feedback(x, p, m, nav, corr)` and `misalignment(...)`.
A model with states appended (`AugmentedModel`: the lever arm, the master delay, nested) asks its
base for `transition_in`, `measurement_in` and `feedback_in` at its own full size, so the arrays
are made once however deep the nesting, and each layer fills or takes its own states.

Conventions shared by all models (nav frame ENU, bodies FLU):
    attitude error   C_est = exp(-[phi x]) C_true ~ (I - [phi x]) C_true
    velocity error   dV = V_est - V_true
    sensor biases    residual after the engine's compensation (body axes), random constants
    lever arm error  dr = r_true - r_used (ship axes)

Discretisation (unless a model says otherwise): for the continuous error dynamics
x' = F x + G w (w white, density Qc) over an IMU interval h with F frozen at the interval's
start attitude, mid-interval rates and mean specific force,
    Phi = I + F h + (F h)^2 / 2          (second order; the interval is 10 ms, |F h| < 1e-3)
    Qd  = G Qc G^T h                     (first order; the sensor noises are isotropic per
                                          triad, so C Qc C^T = Qc and Qd needs no attitude)
Markov states (deck flexure) are discretised exactly (Van Loan); random constants have
Phi = I and no process noise.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from alignment_core.compiled import kernel
from alignment_core.geometry.rotations_compiled import dcm_to_rotvec_k
from alignment_core.navigation.strapdown import NavState

# state kinds, for per-block tuning (the multiple-factor STF's alpha per kind)
PHI, DV, EPS, NABLA, OTHER = 0, 1, 2, 3, 4


@dataclass(slots=True)
class Propagation:
    """One strapdown interval as the error model sees it (nav frame ENU, SI)."""
    c_nb: np.ndarray        # slave attitude at the interval start (nav <- body)
    f_n: np.ndarray         # mean specific force over the interval
    w_ie: np.ndarray        # Earth rate at mid-interval
    w_en: np.ndarray        # transport rate at mid-interval
    v_n: np.ndarray         # slave velocity at the interval end
    lat: float              # rad
    height: float           # m
    h: float                # interval, s


class RateInputs(NamedTuple):
    """The slave's and the master's angular rates over the IMU interval [t_v - h, t_v] that ends
    at a match (rate matching, models/rate_matching.py)."""
    w_b: np.ndarray          # (3,) slave gyro mean rate, bias-compensated (aircraft axes), rad/s
    dtheta: np.ndarray       # (3,) the interval's angle increment, w_b h
    omega_n: np.ndarray      # (3,) inertial rate of the ship (= aircraft) in nav axes, interval mean
    w_n: np.ndarray          # (3,) its master-attitude-dependent part C_m w_m (interval mean)
    w_dot_n: np.ndarray      # (3,) d/dt (C_m w_m): the master rate's change (delay state)
    h: float                 # interval, s


@dataclass(slots=True)
class Match:
    """One matching instant: the master-derived reference for the slave and what it took.

    z_vel is the velocity difference v_slave - v_ref after the lever-arm treatment (the
    Butterworth output under `lever_arm_treatment: butterworth`); r_vel its noise covariance.
    Everything is at the master sample's time of validity (the slave solution `ins` too).
    c_nom: the aircraft's nominal mounting on the deck, C_a^s = Rz(-heading on deck); the
    misalignment is reported relative to C_m c_nom (`nominal_attitude`)."""
    c_m: np.ndarray         # master attitude as reported (nav <- ship body)
    w_m: np.ndarray         # master body rate w.r.t. nav (ship axes)
    r: np.ndarray           # lever arm used in the reference (ship axes)
    u_n: np.ndarray         # C_m (w_m x r + v_LDV): lever-arm plus deck velocity, nav frame
    v_ref: np.ndarray       # master velocity + u_n
    z_vel: np.ndarray       # (3,) velocity difference used as measurement
    r_vel: np.ndarray       # (3, 3) its white-noise covariance
    ins: NavState           # the slave solution at this instant (its time of validity)
    c_nom: np.ndarray | None = None   # nominal aircraft axes in ship axes (heading on deck); None = I
    w_n: np.ndarray | None = None     # master body rate w.r.t. nav in nav axes, C_m w_m (delay state)
    a_n: np.ndarray | None = None     # acceleration of the ship's deck spot, nav frame (delay state); None: unknown
    rate: RateInputs | None = None    # angular rates over the IMU interval ending here (rate matching)

    def with_master_attitude(self, c_m: np.ndarray) -> Match:
        """This match with the master attitude c_m instead (dataclasses.replace's result, in a
        tenth of its time)."""
        return Match(c_m, self.w_m, self.r, self.u_n, self.v_ref, self.z_vel, self.r_vel, self.ins, self.c_nom,
                     self.w_n, self.a_n, self.rate)


@dataclass
class Corrections:
    """What feedback accumulates outside the strapdown: sensor-bias estimates (body axes),
    the lever-arm correction (ship axes) and the mounting estimate (aircraft axes)."""
    bg: np.ndarray = field(default_factory=lambda: np.zeros(3))
    ba: np.ndarray = field(default_factory=lambda: np.zeros(3))
    dr: np.ndarray = field(default_factory=lambda: np.zeros(3))
    mu: np.ndarray = field(default_factory=lambda: np.zeros(3))


class Measurement(NamedTuple):
    """z = H x + v, v ~ N(0, R) (H None and hfun given for a nonlinear measurement)."""
    z: np.ndarray
    h: np.ndarray | None
    r: np.ndarray
    hfun: Callable[[np.ndarray], np.ndarray] | None = None

    def matrix(self) -> np.ndarray:
        """H of a linear measurement (the option wrappers check that their base is linear)."""
        if self.h is None:
            raise TypeError('a nonlinear measurement has no H matrix')
        return self.h


class ErrorModel:
    """Base class: subclasses set the class attributes and implement the methods.

    labels        state names (published in /alignment/state's layout)
    kinds         per state, one of PHI, DV, EPS, NABLA, OTHER (tuning by block)
    attitude      slice of phi in the state
    velocity_rows nav axes (0 E, 1 N, 2 U) of the measurement's velocity rows, in row order
    attitude_rows nav axes of the attitude-match rows that follow them (seed003: all three)
    nonlinear     True: the engine calls propagator() and needs a nonlinear filter
    uses_doppler  True: the engine also matches the Doppler radar (doppler_measurement())
    """
    name: str = ''
    labels: tuple[str, ...] = ()
    kinds: tuple[int, ...] = ()
    attitude: slice = slice(0, 3)
    velocity_rows: tuple[int, ...] = (0, 1, 2)
    nonlinear: bool = False
    uses_doppler: bool = False
    attitude_rows: tuple[int, ...] = ()

    @property
    def n(self) -> int:
        return len(self.labels)

    def initial_covariance(self) -> np.ndarray:
        raise NotImplementedError

    def continuous(self, p: Propagation) -> np.ndarray:
        """F (n, n) of the continuous error dynamics (for tests and documentation)."""
        raise NotImplementedError

    def transition(self, p: Propagation) -> np.ndarray:
        """Phi (n, n) over p.h."""
        fh = self.continuous(p) * p.h
        return np.eye(self.n) + fh + 0.5 * (fh @ fh)

    def transition_in(self, p: Propagation, n: int) -> np.ndarray:
        """Phi in the top-left of an (n, n) identity, n >= self.n (the rows of states appended
        to this model: random constants)."""
        phi = self.transition(p)
        nb = self.n
        if n == nb:
            return phi
        out = np.zeros((n, n))
        out[:nb, :nb] = phi
        out.reshape(-1)[nb * (n + 1)::n + 1] = 1.0         # the appended diagonal
        return out

    def transition_cells(self) -> tuple[np.ndarray, int] | None:
        """(F h's cell indices, n) when `transition_in(p, size)` is velocity matching's compiled
        phi_from_cells(..., cells, n, size) (models/velocity_matching.py), so that the engine can
        compile an IMU interval whole (estimation/propagation_step.py); else None."""
        return None

    def process_noise(self, h: float) -> np.ndarray:
        """Qd (n, n) over an interval h."""
        raise NotImplementedError

    def propagator(self, p: Propagation) -> tuple[Callable, Callable | None]:
        """(fun, jac) with x_(k+1) = fun(x_k) (nonlinear models only)."""
        raise NotImplementedError

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        """z, H (or hfun), R at a matching instant (corr: the current corrections)."""
        raise NotImplementedError

    def measurement_in(self, m: Match, corr: Corrections, n: int) -> Measurement:
        """The measurement with H widened to n >= self.n columns (zero columns for the states
        appended to this model); a linear measurement."""
        meas = self.measurement(m, corr)
        if n == self.n:
            return meas
        h = meas.matrix()
        hh = np.zeros((h.shape[0], n))
        hh[:, :self.n] = h
        return Measurement(meas.z, hh, meas.r)

    def feedback(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        """Apply the estimate x (covariance p) to the strapdown and the corrections; return the
        residual state the filter keeps (zeros for what was fed back)."""
        raise NotImplementedError

    def feedback_in(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        """feedback() of this model's states, the first self.n of a longer state x (covariance p):
        the whole state kept, the appended states as they are, in a new array (the layers that
        appended states write into it)."""
        n = self.n
        if len(x) == n:
            return self.feedback(x, p, m, nav, corr)
        return np.concatenate([self.feedback(x[:n], p[:n, :n], m, nav, corr), x[n:]])

    def misalignment(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState,
                     corr: Corrections) -> tuple[np.ndarray, np.ndarray]:
        """(mu, sigma): the aircraft IMU's estimated misalignment to the master (rotation
        vector, aircraft axes, rad) and its 1-sigma, after feedback; x is the residual state
        feedback() returned, p the covariance after the update."""
        raise NotImplementedError


def rows_of(axes: tuple[int, ...]) -> slice | np.ndarray:
    """What selects the rows `axes` of an array: a slice when they are its first rows in order
    (a view, no copy), else an index array."""
    return slice(0, len(axes)) if axes == tuple(range(len(axes))) else np.array(axes, dtype=np.intp)


def nominal_attitude(m: Match) -> np.ndarray:
    """C_m c_nom: the aircraft attitude the master predicts with zero misalignment."""
    return m.c_m if m.c_nom is None else m.c_m @ m.c_nom


def relative_misalignment(c_m: np.ndarray, c_na: np.ndarray, p_rel: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
    """mu = log(C_m^T C_a) (aircraft axes) and its 1-sigma from the nav-frame covariance p_rel
    of the relative attitude error, rotated to aircraft axes."""
    return relative_misalignment_k(np.ascontiguousarray(c_m, dtype=np.float64),
                                   np.ascontiguousarray(c_na, dtype=np.float64),
                                   np.ascontiguousarray(p_rel, dtype=np.float64))


@kernel
def relative_misalignment_k(c_m, c_na, p_rel):
    """relative_misalignment, compiled: c_m, c_na, p_rel (3, 3) C-ordered float64."""
    c = np.dot(c_m.T, c_na)
    mu = dcm_to_rotvec_k(c[0, 0], c[1, 1], c[2, 2], c[0, 1], c[0, 2], c[1, 0], c[1, 2], c[2, 0], c[2, 1])
    d = np.dot(np.dot(c_na.T, p_rel), c_na)
    return np.array([mu[0], mu[1], mu[2]]), np.sqrt(np.array([d[0, 0], d[1, 1], d[2, 2]]))


class ModelWrapper(ErrorModel):
    """A matching option around a model (models/__init__.py): every method delegates to `base`;
    a subclass overrides what its option changes (rows, states, outputs)."""

    def __init__(self, base: ErrorModel, suffix: str) -> None:
        self.base = base
        self.name = base.name + suffix
        self.labels, self.kinds = base.labels, base.kinds
        self.attitude, self.velocity_rows, self.attitude_rows = base.attitude, base.velocity_rows, base.attitude_rows

    def initial_covariance(self) -> np.ndarray:
        return self.base.initial_covariance()

    def continuous(self, p: Propagation) -> np.ndarray:
        return self.base.continuous(p)

    def transition(self, p: Propagation) -> np.ndarray:
        return self.base.transition(p)

    def transition_cells(self) -> tuple[np.ndarray, int] | None:
        """The base's: a wrapper's Phi is its base's, grown by identity rows (an augmented model's
        appended constants, or ErrorModel.transition_in's); None for a wrapper that computes Phi
        its own way."""
        cls = type(self)
        if cls.transition not in (ModelWrapper.transition, AugmentedModel.transition) \
                or cls.transition_in not in (ErrorModel.transition_in, AugmentedModel.transition_in):
            return None
        return self.base.transition_cells()

    def process_noise(self, h: float) -> np.ndarray:
        return self.base.process_noise(h)

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        return self.base.measurement(m, corr)

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        return self.base.feedback(x, p, m, nav, corr)

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return self.base.misalignment(x, p, m, nav, corr)


class AugmentedModel(ModelWrapper):
    """`base` + random-constant states appended (dx' = 0, no process noise, prior `sigma` each):
    Phi, Qd and P0 grow by a block; the base keeps its own states. Subclasses add the
    measurement columns and say what feedback does with the new states."""

    def __init__(self, base: ErrorModel, suffix: str, labels: tuple[str, ...], sigma: float) -> None:
        if base.nonlinear:
            raise ValueError(f'{suffix.lstrip("+")} states need a linear base model, not {base.name}')
        super().__init__(base, suffix)
        self.labels = base.labels + labels
        self.kinds = base.kinds + (OTHER,) * len(labels)
        self.nb = base.n
        self.sigma = float(sigma)
        self._qd: dict[float, np.ndarray] = {}

    def _grow(self, a: np.ndarray, corner: float) -> np.ndarray:
        """a (nb, nb) in the top-left of this model's (n, n) zero matrix, `corner` on the
        diagonal below it."""
        n = self.n
        out = np.zeros((n, n))
        out[:self.nb, :self.nb] = a
        for k in range(self.nb, n):
            out[k, k] = corner
        return out

    def initial_covariance(self) -> np.ndarray:
        return self._grow(self.base.initial_covariance(), self.sigma ** 2)

    def continuous(self, p: Propagation) -> np.ndarray:
        return self._grow(self.base.continuous(p), 0.0)

    def transition(self, p: Propagation) -> np.ndarray:
        return self.base.transition_in(p, self.n)

    def transition_in(self, p: Propagation, n: int) -> np.ndarray:
        """The innermost non-augmented model's Phi with identity rows for every state appended
        above it, grown once however many augmentations are nested (lever arm on delay)."""
        return self.base.transition_in(p, n)

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            qd = self._qd[h] = self._grow(self.base.process_noise(h), 0.0)
        return qd

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        return self.measurement_in(m, corr, self.n)

    def measurement_in(self, m: Match, corr: Corrections, n: int) -> Measurement:
        """The base's measurement, H widened once to n columns, this model's columns filled
        (`fill_columns`), however many augmentations are nested."""
        meas = self.base.measurement_in(m, corr, n)
        self.fill_columns(meas.matrix(), m)
        return meas

    def fill_columns(self, h: np.ndarray, m: Match) -> None:
        """Write this model's columns of H (rows x n; the appended states from column nb)."""
        raise NotImplementedError

    def feedback(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        return self.feedback_in(x, p, m, nav, corr)

    def feedback_in(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        """The base's feedback_in, then what this layer does with its own states (each says)."""
        raise NotImplementedError

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return self.base.misalignment(x[:self.nb], p[:self.nb, :self.nb], m, nav, corr)
