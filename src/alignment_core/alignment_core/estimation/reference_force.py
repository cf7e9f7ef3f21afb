"""The specific force the error model couples attitude into velocity with, taken from the
reference (`filter.specific_force: reference`; docs/carrier.md, "heading on a beam").

The velocity error grows as dV' = [f^n x] phi. The slave's own f^n is C_est f_b = (I - [phi x])
f_true: its horizontal part carries g x the slave's tilt error, a quantity the filter is itself
uncertain about. Where the deck's horizontal acceleration is small (a carrier: 0.04-0.08 m/s^2
RMS, g x 15' of tilt) that product dominates the heading's coupling, and the filter, treating it
as a known coefficient, credits heading with information it does not have (its heading sigma
collapses and small unmodelled velocity residuals go into heading). Parked, the aircraft's
horizontal specific force is the deck spot's (the gear's and the flexure's own accelerations
are zero-mean vibration), which the master gives independently of the slave's errors:
    f_h = a_spot,h + [(2 w_ie + w_en) x v]_h,  a_spot = d/dt (v_m + C_m (w_m x r)),
the derivative of a quadratic least-squares fit over the last `window_s` of master samples,
taken at the newest (causal; at 1 mm/s of master velocity noise, 50 Hz and 1 s: about 2e-3 m/s^2
of noise, 5e-3 m/s^2 RMS in all at sea state 5, against g x the slave's tilt error).
"""
from __future__ import annotations

import numpy as np

from alignment_core.compiled import as_float64, kernel
from alignment_core.geometry.rotations import cross_f, floats

MIN_FILL = 0.8
"""The fit is used once its samples span this fraction of the window (None before)."""


class SpotAcceleration:
    """Causal estimate of the deck spot's nav-frame acceleration (3,) m/s^2 from the master
    samples (module docstring): the spot's velocity C_m (v_m + w_m x r) of every sample in the
    window, with the newest sample's lever arm r (the master's part of the reference: the LDV's
    relative velocity is not the spot's), fitted by a quadratic in time.

    The window's samples live in arrays (rows [start, end) of a buffer that doubles when full):
    the velocity rows of the whole window are recomputed when the arm moves (a filter estimating
    the arm moves it at every update), else only the new samples' (spot_slope)."""

    def __init__(self, window_s: float) -> None:
        if not window_s > 0.0:
            raise ValueError(f'window_s must be > 0, got {window_s}')
        self._window_ns = int(round(window_s * 1e9))
        self._t = np.zeros(0, dtype=np.int64)        # (cap,) ns
        self._c = np.zeros((0, 3, 3))                # (cap, 3, 3) nav <- ship
        self._vw = np.zeros((0, 2, 3))               # (cap, 2, 3) velocity and body rate, ship axes
        self._rows = np.zeros((0, 3))                # (cap, 3) the spot's velocity with the arm _rows_r
        self._start = self._end = self._rows_end = 0
        self._rows_r = np.zeros(3)                   # the arm the rows [., _rows_end) were made with
        self._value: np.ndarray | None = None

    def clear(self) -> None:
        """Forget the samples (a gap): no value until the window refills."""
        self._start = self._end = self._rows_end = 0
        self._value = None

    def _make_room(self) -> None:
        """Move the window to the buffer's start, doubling the buffer if the window fills it."""
        s, e = self._start, self._end
        n = e - s
        cap = max(64, 2 * n) if n >= len(self._t) // 2 else len(self._t)
        for name in ('_t', '_c', '_vw', '_rows'):
            old = getattr(self, name)
            new = old if cap == len(old) else np.zeros((cap,) + old.shape[1:], dtype=old.dtype)
            new[:n] = old[s:e]
            setattr(self, name, new)
        self._rows_end = max(self._rows_end - s, 0)
        self._start, self._end = 0, n

    def add(self, t_ns: int, c_m: np.ndarray, v_b: np.ndarray, w_b: np.ndarray, r: np.ndarray) -> None:
        """One master sample valid at t_ns (increasing times; an older or equal one is ignored):
        attitude C_m (3, 3) nav <- ship, velocity and body rate (3,) ship axes, lever arm r (3,) m.
        The fit is made at once, in the same call (its readers, the IMU steps while parked and
        the delay state, read it after nearly every master sample)."""
        r = np.ascontiguousarray(r, dtype=float)
        if r.shape != (3,):
            raise ValueError(f'the lever arm must be a 3-vector, got shape {r.shape}')
        self.take(*append_and_fit(*self.buffers(), r, t_ns, as_float64(c_m), as_float64(v_b), as_float64(w_b)))

    def buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int, int, int, float]:
        """append_and_fit's arguments before the arm, with room for one more sample (a caller
        that computes the arm in the same compiled call: estimation/reference_velocity.py)."""
        if self._end == len(self._t):
            self._make_room()
        return (self._t, self._c, self._vw, self._rows, self._rows_r, self._rows_end, self._start, self._end,
                self._window_ns, MIN_FILL * self._window_ns)

    def take(self, start: int, fitted: bool, value: np.ndarray) -> None:
        """append_and_fit's outcome for the buffers `buffers` gave."""
        if start < 0:
            return
        self._start, self._end = start, self._end + 1
        self._value = value if fitted else None
        if fitted:
            self._rows_end = self._end

    def acceleration(self) -> np.ndarray | None:
        """d v / dt (3,) at the newest sample, or None while the samples span less than MIN_FILL
        of the window (or are fewer than four)."""
        return self._value


@kernel
def append_sample(t, c, vw, start, end, t_ns, c_m, v_b, w_b, window_ns):
    """Write a master sample valid at t_ns into row `end` of the window's buffers (t (cap,) ns,
    c (cap, 3, 3), vw (cap, 2, 3), with room for it) and return the window's new first row (the
    samples more than window_ns older dropped), or -1 when t_ns is not after the newest sample
    (nothing written)."""
    if end > start and t_ns <= t[end - 1]:
        return -1
    t[end] = t_ns
    for a in range(3):
        for b in range(3):
            c[end, a, b] = c_m[a, b]
        vw[end, 0, a] = v_b[a]
        vw[end, 1, a] = w_b[a]
    while t_ns - t[start] > window_ns:
        start += 1
    return start


@kernel
def append_and_fit(t, c, vw, rows, rows_r, rows_end, start, end, window_ns, min_span_ns, r, t_ns, c_m, v_b, w_b):
    """append_sample of a master sample, then, once the window's samples are four or more and
    span min_span_ns, spot_slope over it with the rows from rows_end on made anew (from its first
    row when the arm r (3,) is not, bit for bit, the arm rows_r (3,) they were made with; none
    are kept before the first fit, rows_end 0); when fitted, rows_r is r after. Returns (the
    window's first row, or -1 when nothing was appended; whether it was fitted; the slope (3,),
    empty when not)."""
    s = append_sample(t, c, vw, start, end, t_ns, c_m, v_b, w_b, window_ns)
    if s < 0:
        return s, False, np.empty(0)
    e = end + 1
    if e - s < 4 or t[e - 1] - t[s] < min_span_ns:
        return s, False, np.empty(0)
    moved = False
    bits, known_bits = r.view(np.int64), rows_r.view(np.int64)
    for i in range(3):
        moved = moved or bits[i] != known_bits[i]
    slope = spot_slope(t, c, vw, rows, r, s if moved else max(rows_end, s), s, e)
    for i in range(3):
        rows_r[i] = r[i]
    return s, True, slope


@kernel
def spot_slope(t, c, vw, rows, r, k, s, e):
    """The slope at t[e - 1] (3,) of the quadratic least-squares fit to the velocity rows
    [s, e) over times t (ns); rows [k, e) are first made from the attitudes c (., 3, 3),
    ship-axes velocities and rates vw (., 2, 3) and the arm r (3,): C (v + w x r).

    The fit is taken in the polynomials orthogonal over the window's times (Forsythe's three-term
    recurrence in tau = t - t[e - 1], s): p0 = 1, p1 = tau - a1, p2 = (tau - a2) p1 - b1, with
    a1 = mean(tau), a2 = sum(tau p1^2) / sum(p1^2), b1 = sum(p1^2) / n. The coefficients are
    independent projections d_j = sum(y p_j) / sum(p_j^2) (no normal matrix to invert), and the
    slope at tau = 0 is d1 p1'(0) + d2 p2'(0) = d1 - (a1 + a2) d2. Needs four or more distinct times."""
    r0, r1, r2 = r[0], r[1], r[2]
    for i in range(k, e):
        w0, w1, w2 = vw[i, 1, 0], vw[i, 1, 1], vw[i, 1, 2]
        x0 = vw[i, 0, 0] + (w1 * r2 - w2 * r1)
        x1 = vw[i, 0, 1] + (w2 * r0 - w0 * r2)
        x2 = vw[i, 0, 2] + (w0 * r1 - w1 * r0)
        for a in range(3):
            rows[i, a] = c[i, a, 0] * x0 + c[i, a, 1] * x1 + c[i, a, 2] * x2
    n = e - s
    tau = np.empty(n)
    mean = 0.0
    for i in range(n):
        tau[i] = (t[s + i] - t[e - 1]) * 1e-9
        mean += tau[i]
    a1 = mean / n
    s11 = 0.0
    m2 = 0.0
    for i in range(n):
        p1 = tau[i] - a1
        s11 += p1 * p1
        m2 += tau[i] * p1 * p1
    a2 = m2 / s11
    b1 = s11 / n
    s22 = 0.0
    y1 = np.zeros(3)
    y2 = np.zeros(3)
    for i in range(n):
        p1 = tau[i] - a1
        p2 = (tau[i] - a2) * p1 - b1
        s22 += p2 * p2
        for a in range(3):
            y = rows[s + i, a]
            y1[a] += y * p1
            y2[a] += y * p2
    out = np.empty(3)
    for a in range(3):
        out[a] = y1[a] / s11 - (a1 + a2) * (y2[a] / s22)
    return out


def reference_specific_force(f_slave_n: np.ndarray, a_spot_n: np.ndarray, v_n: np.ndarray,
                             w_ie: np.ndarray, w_en: np.ndarray) -> np.ndarray:
    """(3,) the specific force for the error model: the slave's vertical, the horizontal (E, N)
    from the spot's acceleration plus the Coriolis and transport terms (ENU: gravity is vertical)."""
    ie, en = floats(w_ie), floats(w_en)
    cx, cy, _ = cross_f((2.0 * ie[0] + en[0], 2.0 * ie[1] + en[1], 2.0 * ie[2] + en[2]), floats(v_n))
    ax, ay, _ = floats(a_spot_n)
    return np.array((ax + cx, ay + cy, float(f_slave_n[2])))      # Python floats: numpy's bits, a third of its time
