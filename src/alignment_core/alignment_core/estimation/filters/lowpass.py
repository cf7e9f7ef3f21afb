"""Causal Butterworth low-pass for seed 002's lever-arm treatment (`lever_arm_treatment:
butterworth`): the velocity-matching difference v_slave - v_ref (reference without the
lever-arm term) is low-pass filtered before it reaches the Kalman filter.

Seed 002's filter is scipy.signal.butter(2, 0.0101) at 100 Hz: cut-off 0.0101 x 50 Hz = 0.505 Hz
(it prints G(z) = (2.453e-4 + 4.906e-4 z^-1 + 2.453e-4 z^-2) / (1 - 1.9551 z^-1 + 0.9562 z^-2), rounded).
Bilinear design: DC gain exactly 1, |H|^2 = 1 / (1 + (tan(w/2) / tan(w_c/2))^(2N)), so -3.01 dB
at the cut-off. It is run in transposed direct form II, the operations of scipy.signal.lfilter
in the same order, one sample per matching instant, its state carried across steps: stepping
and one lfilter call over the whole record give identical numbers. It starts in the steady
state of its first input (no start-up transient).

What it does and does not do: the lever-arm velocity on a ship (periods 7-18 s, 0.05-0.15 Hz)
lies far below a 0.5 Hz cut-off, so it passes almost unchanged; the filter removes only
faster disturbances. It also delays the whole difference -- the dV the Kalman filter estimates
included -- by about 0.3 s of group delay at low frequency, a lag the error model does not
contain (the paper's approach; reported as is, not corrected).

Closed-loop feedback moves the slave velocity by a step c after an update. `shift(c)` moves
the filter's memory by the same step (as if the whole past input had been c different: state
+= c times the unit-input steady state), so the filtered difference does not keep reporting a
velocity error that was already fed back.
"""
from __future__ import annotations

import numpy as np


class ButterworthLowPass:
    """order-N Butterworth low-pass on `channels` parallel signals sampled at rate_hz."""

    def __init__(self, cutoff_hz: float, rate_hz: float, channels: int = 3, order: int = 2) -> None:
        wn = cutoff_hz / (0.5 * rate_hz)
        if not 0.0 < wn < 1.0:
            raise ValueError(f'cut-off {cutoff_hz} Hz must be in (0, {0.5 * rate_hz}) Hz (Nyquist)')
        self.cutoff_hz = float(cutoff_hz)
        self.rate_hz = float(rate_hz)
        # imported here: scipy.signal would add ~1 s to the start-up of every node that imports the engine
        from scipy.signal import butter, lfilter_zi
        b, a = butter(order, wn)
        self.b, self.a = b / a[0], a / a[0]
        self.zi_unit = lfilter_zi(self.b, self.a)          # (order,) steady state for unit input
        self.channels = channels
        self.z: np.ndarray | None = None                    # (order, channels)

    def step(self, x: np.ndarray) -> np.ndarray:
        """Filter one sample (channels,); returns the output sample."""
        x = np.asarray(x, dtype=float)
        if self.z is None:
            self.z = np.outer(self.zi_unit, x)
        b, a, z = self.b, self.a, self.z
        y = z[0] + b[0] * x
        last = len(b) - 1
        for i in range(last - 1):
            z[i] = z[i + 1] + x * b[i + 1] - y * a[i + 1]
        z[last - 1] = x * b[last] - y * a[last]
        return y

    def shift(self, c: np.ndarray) -> None:
        """Add the constant c (channels,) to the remembered input history."""
        if self.z is not None:
            self.z = self.z + np.outer(self.zi_unit, c)

    def batch(self, xs: np.ndarray) -> np.ndarray:
        """The same filter over a whole record (K, channels) by scipy.signal.lfilter (reference)."""
        from scipy.signal import lfilter
        xs = np.asarray(xs, dtype=float)
        y, _ = lfilter(self.b, self.a, xs, axis=0, zi=np.outer(self.zi_unit, xs[0]))
        return y

    def gain(self, f_hz: np.ndarray) -> np.ndarray:
        """|H(e^(j 2 pi f / rate))| of the discrete filter."""
        zi = np.exp(-2j * np.pi * np.asarray(f_hz, dtype=float) / self.rate_hz)
        num = np.polyval(self.b[::-1], zi)
        den = np.polyval(self.a[::-1], zi)
        return np.abs(num / den)
