"""The histories' interpolations between two samples, and the carry of a feedback to a stored
slave solution, compiled (navigation/history.py): the same operations as the numpy and float code
they replace, bit for bit (compiled.py), in one call each instead of a dozen numpy calls. The
slave's solutions are float64 (the strapdown's and the feedback's); the LDV history keeps its
interpreted code for a float32 sample, which numpy would interpolate in float32."""
from __future__ import annotations

import math

import numpy as np

from alignment_core.compiled import kernel
from alignment_core.geometry.rotations_compiled import normalized_k, quat_mul_k, quat_to_rotvec_k, rotvec_to_quat_k


@kernel
def slave_between_k(q_a, q_b, v_a, v_b, f, phi):
    """(q, v, Phi from there): the attitude a fraction f (0 < f < 1) of the way from q_a to q_b
    (4,) (rotations.slerp), the velocity as far from v_a to v_b (3,) (numpy's v_a + f (v_b - v_a)),
    and the transition of the step cut there, I + (1 - f) (Phi - I), for the step's transition
    phi (n, n) (an empty array when it has none)."""
    a = (q_a[0], q_a[1], q_a[2], q_a[3])
    rx, ry, rz = quat_to_rotvec_k(quat_mul_k((-a[0], -a[1], -a[2], a[3]), (q_b[0], q_b[1], q_b[2], q_b[3])))
    q = np.array(normalized_k(quat_mul_k(a, rotvec_to_quat_k(f * rx, f * ry, f * rz))))
    v = np.empty(3)
    for i in range(3):
        v[i] = v_a[i] + f * (v_b[i] - v_a[i])
    n = phi.shape[0]
    eye = np.eye(n)
    return q, v, eye + (1.0 - f) * (phi - eye)


@kernel
def carried_k(q0, q1, v0, v1, q, v):
    """A stored solution's (q (4,), v (3,)) after the feedback that took the live one from
    (q0, v0) to (q1, v1): q turned by the nav-frame rotation q1 q0^-1 and renormalised, v moved by
    v1 - v0 (the float forms' and numpy's operations in their order: rotations.py)."""
    c = quat_mul_k((q1[0], q1[1], q1[2], q1[3]), (-q0[0], -q0[1], -q0[2], q0[3]))
    q_new = np.array(normalized_k(quat_mul_k(c, (q[0], q[1], q[2], q[3]))))
    v_new = np.empty(3)
    for i in range(3):
        v_new[i] = v[i] + (v1[i] - v0[i])
    return q_new, v_new


@kernel
def ldv_between_k(v_a, v_b, f, disp_a, dt, v_p, rho, threshold, beam_a, beam_b):
    """The LDV between two valid samples a and b (3,) at the fraction f of [a, b]: (velocity,
    deck displacement after dt s from a (an empty array for dt < 0: not moving, a's own), the
    interpolation error variance from the kink against the sample p before a (v_p; empty: none)
    with b's spacing over a's, rho, and the noise threshold, and the unit line of sight
    interpolated between beam_a and beam_b (empty: a vector LDV))."""
    v = v_a + f * (v_b - v_a)
    disp = np.empty(0)
    if dt >= 0.0:
        disp = disp_a + 0.5 * (v_a + v) * dt
    var = 0.0
    if v_p.shape[0] == 3:
        delta = v_b - (1.0 + rho) * v_a + rho * v_p
        excess = float(np.dot(delta, delta)) - threshold
        if excess > 0.0:
            var = excess * f * f
    beam = np.empty(0)
    if beam_a.shape[0] == 3:
        u = beam_a + f * (beam_b - beam_a)
        beam = u / math.sqrt(np.dot(u, u))
    return v, disp, var, beam
