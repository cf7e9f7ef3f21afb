"""Placing the slave on the master: the slave solution a master sample gives at initialisation
and after a bridged IMU gap, and the covariance over a gap (docs/engine.md, IMU gaps).

On the deck the aircraft rides the ship rigidly, so the relative attitude C_m^T C_a of the last
match before a gap still holds after it: the slave is carried across the gap by the master's own
motion, C_a(t) = C_m(t) (C_m(t0)^T C_a(t0)), its velocity and position set from the reference.
Its attitude error is then the one it had before the gap (the covariance propagated over the gap
says how much it grew); its velocity error is the reference's, uncorrelated with the rest."""
from __future__ import annotations

import dataclasses
from typing import cast

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.estimation.filter_factory import EngineFilter
from alignment_core.estimation.filters.base import NonlinearFilter
from alignment_core.estimation.matching import Reference
from alignment_core.estimation.models import ErrorModel, Propagation
from alignment_core.estimation.models.base import DV
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.samples import MasterSample


def slave_from_master(plane: earth.TangentPlane, m: MasterSample, ref: Reference, c_a: np.ndarray) -> Strapdown:
    """The slave at the master's validity time: attitude c_a (nav <- aircraft), the reference
    velocity, and the position of the lever arm's end (the master's position carried along it)."""
    c_m = ref.c_m
    lat, lon, h = plane.to_geodetic(m.p_w + plane.c_local_to_world(m.p_w) @ (c_m @ ref.r))
    q = Rotation.from_matrix(c_a).as_quat()
    return Strapdown(NavState(q_nb=q, v_n=ref.v_ref.copy(), lat=float(lat), lon=float(lon), h=float(h)))


def carried_attitude(c_m: np.ndarray, anchor: tuple[np.ndarray, np.ndarray] | None,
                     c_nom: np.ndarray | None) -> np.ndarray:
    """C_m(t) C_m(t0)^T C_a(t0) from the last match's (C_m(t0), q_a(t0)); without one, the
    nominal mounting C_m c_nom (as at initialisation)."""
    if anchor is None:
        return c_m if c_nom is None else c_m @ c_nom
    c_m0, q_a0 = anchor
    return c_m @ (c_m0.T @ quat_to_dcm(q_a0))


def dead_reckoned(st: NavState, h: float) -> NavState:
    """The solution carried h seconds on at its velocity, attitude held (a gap while moving);
    the strapdown's coning and sculling memory starts afresh."""
    r_m, r_n = earth.radii(st.lat)
    e, n, u = (float(v) * h for v in st.v_n)
    return NavState(q_nb=st.q_nb, v_n=st.v_n, lat=st.lat + n / (float(r_m) + st.h),
                    lon=st.lon + e / ((float(r_n) + st.h) * float(np.cos(st.lat))), h=st.h + u)


def bridge_covariance(kf: EngineFilter, model: ErrorModel, prop: Propagation | None, h: float) -> None:
    """Propagate the filter over h seconds without data: the transition of the last IMU step (its
    specific force and rates) stretched to h, and the process noise of h (no strapdown step)."""
    qd = model.process_noise(h)
    if prop is None:
        kf.P = kf.P + qd
        return
    p = dataclasses.replace(prop, h=h)
    if model.nonlinear:
        fun, jac = model.propagator(p)
        cast(NonlinearFilter, kf).predict_nonlinear(fun, qd, jac)
    else:
        kf.predict(model.transition(p), qd)


def reset_velocity(kf: EngineFilter, model: ErrorModel, variance: float) -> None:
    """The slave's velocity was set from the reference: its velocity error states become zero with
    the reference's variance, uncorrelated with the other states."""
    idx = [i for i, k in enumerate(model.kinds) if k == DV]
    if not idx:
        return
    p = np.array(kf.P, dtype=float)
    p[idx, :] = 0.0
    p[:, idx] = 0.0
    p[idx, idx] = variance
    x = np.array(kf.x, dtype=float)
    x[idx] = 0.0
    kf.P = p.astype(kf.P.dtype)
    kf.x = x.astype(kf.x.dtype)
