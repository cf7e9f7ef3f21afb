"""The cubic Hermite of an IMU interval at its quadrature nodes, compiled: through the values and
rates at the interval's two ends, its value, rate and integral from the interval's start at the
nodes, with numpy's bits (each node's products and sums in the order numpy forms them), for the
aircraft's ideal increments (aircraft/kinematics.py)."""
from __future__ import annotations

import math

import numpy as np

from alignment_core.compiled import kernel


def hermite_basis(u: np.ndarray) -> np.ndarray:
    """The cubic Hermite basis at the nodes u (J,), its derivative and its integral from 0 to u:
    (3, 4, J)."""
    uu = u[None, :, None]
    rows = [[2*uu**3 - 3*uu**2 + 1, uu**3 - 2*uu**2 + uu, -2*uu**3 + 3*uu**2, uu**3 - uu**2],
            [6*uu**2 - 6*uu, 3*uu**2 - 4*uu + 1, -6*uu**2 + 6*uu, 3*uu**2 - 2*uu],
            [uu**4/2 - uu**3 + uu, uu**4/4 - 2*uu**3/3 + uu**2/2, -uu**4/2 + uu**3, uu**4/4 - uu**3/3]]
    return np.array([[b[0, :, 0] for b in r] for r in rows])


@kernel
def hermite_nodes(x0, dx0, x1, dx1, h, basis):
    """The cubic Hermite through (x0, dx0) and (x1, dx1) (K, 3) over intervals h (K,) at J nodes:
    its value, rate and integral from the interval's start, (n, K, J, 3) for the first n rows of
    basis (n, 4, J) (hermite_basis). One pass, each node's products and sums in numpy's order."""
    n, m = basis.shape[0], basis.shape[2]
    k_n = x0.shape[0]
    if not (x0.shape == (k_n, 3) and dx0.shape == (k_n, 3) and x1.shape == (k_n, 3) and dx1.shape == (k_n, 3)):
        raise ValueError('hermite_nodes: the ends (K, 3) of K intervals')
    if h.shape[0] != k_n or basis.shape[1] != 4 or n > 3:
        raise ValueError('hermite_nodes: K interval lengths and a basis (n <= 3, 4, J)')
    out = np.empty((n, k_n, m, 3))
    for k in range(x0.shape[0]):
        hk = h[k]
        for r in range(n):
            for j in range(m):
                b0, b1, b2, b3 = basis[r, 0, j], basis[r, 1, j] * hk, basis[r, 2, j], basis[r, 3, j] * hk
                for c in range(3):
                    y = b0 * x0[k, c] + b1 * dx0[k, c] + b2 * x1[k, c] + b3 * dx1[k, c]
                    out[r, k, j, c] = y if r == 0 else (divided(y, hk) if r == 1 else hk * y)
    return out


@kernel
def divided(y, d):
    """y / d with numpy's bits for d = 0 (y times an infinity of d's sign: the quotient's
    infinity, the CPU's NaN for 0 / 0, a NaN y passed on), where a kernel's own division raises
    (compiled.py: Python's error model)."""
    if d != 0.0:
        return y / d
    return y * math.copysign(math.inf, d)
