"""The velocities a master sample predicts for the slave (estimation/matching.py's reference): the
master's attitude, the lever arm to the aircraft's spot with the deck displacement, the spot's
velocity relative to the master and the velocity the slave should have, in one compiled call,
with the master sample into the deck spot's fit (reference_force.py) in the same call where the
engine fits it."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from alignment_core.compiled import kernel
from alignment_core.estimation.reference_force import append_and_fit
from alignment_core.geometry.rotations_compiled import cross_k, quat_to_dcm_k

DISPLACEMENT, SURVEYED, SURVEYED_CORRECTED = 0, 1, 2   # what the reference's lever arm adds to the deck's displacement


class Reference(NamedTuple):
    """What a master sample predicts for the slave at its validity time (nav frame, SI)."""
    c_m: np.ndarray          # (3, 3) master attitude, nav <- ship body
    r: np.ndarray            # (3,) lever arm used (ship axes), deck displacement included
    v_rel: np.ndarray        # (3,) LDV velocity relative to the deck (zero while parked)
    u_n: np.ndarray          # (3,) C_m (w_m x r + v_rel)
    v_ref: np.ndarray        # (3,) master velocity + u_n
    moving: bool             # the LDV at the validity time says the aircraft moves
    beam_n: np.ndarray | None = None   # (3,) a beam LDV's unit line of sight, nav frame (models/beam.py)
    w_n: np.ndarray | None = None      # (3,) the master's body rate in nav axes, C_m w_b (BLAS's; None: not made)


@kernel
def reference_velocities(q_nb, w_b, v_b, r0, dr, disp, arm, v_rel, beam):
    """(C_m (3, 3), the lever arm r, u_n = C_m (w_b x r + v_rel), v_ref = C_m v_b + u_n, C_m beam, C_m w_b)
    of a master sample's quaternion q_nb (4,), body rate w_b and velocity v_b (3,), with the LDV
    velocity v_rel and its line of sight beam (3,, ship axes; empty for a vector LDV: an empty
    result): the reference's attitude, the spot's velocity relative to the master, the velocity
    the slave should have and the beam in nav axes. The lever arm (ship axes) is the deck
    displacement disp (3,) alone (arm DISPLACEMENT), after the surveyed spot r0 (SURVEYED) or
    after r0 and its estimated correction dr (SURVEYED_CORRECTED: (r0 + dr) + disp). Also the
    master's rate in nav axes C_m w_b, the delay state's (numpy's C_m @ w_b: the same BLAS gemv).
    One kernel for what were eleven numpy calls."""
    if arm == DISPLACEMENT:
        r = disp.copy()
    elif arm == SURVEYED:
        r = r0 + disp
    else:
        r = r0 + dr + disp
    c_m = np.array(quat_to_dcm_k((q_nb[0], q_nb[1], q_nb[2], q_nb[3]))).reshape(3, 3)
    rel = np.array(cross_k((w_b[0], w_b[1], w_b[2]), (r[0], r[1], r[2]))) + v_rel
    u_n = np.dot(c_m, rel)
    beam_n = np.dot(c_m, beam) if beam.shape[0] == 3 else np.empty(0)
    return c_m, r, u_n, np.dot(c_m, v_b) + u_n, beam_n, np.dot(c_m, w_b)


@kernel
def reference_and_fit(q_nb, w_b, v_b, r0, dr, disp, arm, v_rel, beam, t, c, vw, rows, rows_r, rows_end, start, end,
                      window_ns, min_span_ns, t_ns):
    """reference_velocities, then the master sample valid at t_ns into the deck spot's fit with
    the reference's C_m and lever arm (reference_force.append_and_fit, its buffers from t on: what
    SpotAcceleration.add does): both calls' results, in one call."""
    c_m, r, u_n, v_ref, beam_n, w_n = reference_velocities(q_nb, w_b, v_b, r0, dr, disp, arm, v_rel, beam)
    start1, fitted, slope = append_and_fit(t, c, vw, rows, rows_r, rows_end, start, end, window_ns, min_span_ns, r,
                                           t_ns, c_m, v_b, w_b)
    return c_m, r, u_n, v_ref, beam_n, w_n, start1, fitted, slope
