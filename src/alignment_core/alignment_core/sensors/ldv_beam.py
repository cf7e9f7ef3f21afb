"""The LDV as a beam (`ldv.mode: beam`): a head fixed on the deck tracks a retro-reflector on the
aircraft and measures the velocity component along its line of sight, the range rate.

Geometry (ship axes s, FLU; aircraft axes a): the head at m (`mount_m`), the reflector at
rho (`reflector_m`, aircraft axes, from the IMU), so with the IMU at r (ship axes)
    d = r + C_a^s rho - m,       u = d / |d|       (the line of sight, head -> reflector)
    s = u . d'(t)  = d|d|/dt     (d' the derivative in ship axes: the head does not move there)
    d' = v_rel + C_a^s (w_sa x rho),   w_sa = w_a - C_s^a w_s   (aircraft rate relative to the ship)
with v_rel the IMU spot's velocity relative to the deck (sensors/ldv.py). A rigid aircraft has
w_sa = 0 and the reflector moves as the IMU spot does; an aircraft rocking on its gear does not.

Blockage (a simple geometric model): no return when the reflector, a corner cube facing
`reflector_axis` (aircraft axes), sees the head more than `reflector_halfangle_deg` off that
axis (the airframe hides it, or the aircraft has passed the head), or when the head is nearer
than `min_range_m`. Transient blockage (deck crew, vehicles crossing the line) is the LDV's
two-state Markov dropout process (sensors/ldv.py), shared with the vector mode.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.geometry.rotations import cross


def line_of_sight(c_ns: Rotation, q_a: np.ndarray, r: np.ndarray, v_rel: np.ndarray, w_s: np.ndarray,
                  w_a: np.ndarray | None, mount: np.ndarray, reflector: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(u (K, 3) unit line of sight head -> reflector in ship axes, range (K,), range rate (K,),
    reflector axis resolution C_a^s (K, 3, 3)) for K samples: c_ns the ship's C_n^s, q_a the
    aircraft attitudes (nav <- aircraft, scalar-last), r the IMU spots and v_rel their
    velocities relative to the deck (ship axes), w_s the ship's and w_a the aircraft's body rates
    w.r.t. nav (own axes; None: rigid on the ship)."""
    c_as = (c_ns * Rotation.from_quat(q_a)).as_matrix()                 # C_a^s = C_n^s C_a^n
    arm = np.einsum('kij,j->ki', c_as, reflector)
    d = r + arm - mount
    rng = np.linalg.norm(d, axis=1)
    u = d / np.where(rng > 0.0, rng, 1.0)[:, None]
    d_dot = v_rel.copy()
    if w_a is not None and np.any(reflector):
        w_sa = w_a - np.einsum('kji,kj->ki', c_as, w_s)              # C_s^a w_s = (C_a^s)^T w_s
        d_dot += np.einsum('kij,kj->ki', c_as, cross(w_sa, np.broadcast_to(reflector, w_sa.shape)))
    return u, rng, np.einsum('ki,ki->k', u, d_dot), c_as


def visible(u: np.ndarray, rng: np.ndarray, c_as: np.ndarray, axis: np.ndarray, halfangle_rad: float,
            min_range_m: float) -> np.ndarray:
    """True where the head sees the reflector (module docstring): the direction reflector -> head,
    -u, within the half-angle of the reflector's facing axis, and the head not nearer than
    min_range_m."""
    facing = np.einsum('kij,j->ki', c_as, axis / np.linalg.norm(axis))
    return (np.einsum('ki,ki->k', -u, facing) >= np.cos(halfangle_rad)) & (rng >= min_range_m)
