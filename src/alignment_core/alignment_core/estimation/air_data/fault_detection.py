"""Port fault detection from the filter's innovations: each port's normalised innovation squared
(y_i^2 / S_ii, chi-square with 1 degree of freedom when the port is healthy) summed over a
sliding window of n frames (n >= MIN_SAMPLES) is chi-square with n degrees of freedom; the worst
port whose sum exceeds its (1 - false_alarm) quantile is declared failed. And, when a whole frame
fails the gate, leave-one-out: if the frame passes without one port (its NIS over the others
below their 99.9 % quantile, and at most AMBIGUITY times the NIS without any other port: the
bottom and top ports of a meridian can explain each other's fault) that port is the suspect;
SUSPECT_FRAMES suspect frames in a row
declare it failed (a blocked port in turbulence is seen this way long before its own
innovations, inflated by the frames the gate refused, add up)."""
from __future__ import annotations

from collections import deque

import numpy as np
from scipy.stats import chi2

MIN_SAMPLES = 5
SUSPECT_FRAMES = 5
AMBIGUITY = 0.25


class PortFaultDetector:
    def __init__(self, n_ports: int, window_s: float, false_alarm: float) -> None:
        self.window_s = float(window_s)
        self.limits = {n: float(chi2.ppf(1.0 - false_alarm, n)) for n in range(MIN_SAMPLES, 2000)}
        self._suspect: int | None = None
        self._count = 0
        self._hist: list[deque[tuple[float, float]]] = [deque() for _ in range(n_ports)]
        self.detections: list[tuple[float, int]] = []

    def add(self, t: float, ports: np.ndarray, normalised: np.ndarray) -> int | None:
        """Record one frame's normalised innovations of `ports`; the port declared failed, or None."""
        worst, worst_excess = None, 1.0
        for i, v in zip(ports.tolist(), normalised.tolist()):
            h = self._hist[i]
            h.append((t, v))
            while len(h) > MIN_SAMPLES and t - h[0][0] > self.window_s:
                h.popleft()
            if MIN_SAMPLES <= len(h) < 2000:
                excess = sum(x for _, x in h) / self.limits[len(h)]
                if excess > worst_excess:
                    worst, worst_excess = i, excess
        if worst is not None:
            self.detections.append((t, worst))
            self._hist[worst].clear()
        return worst

    def leave_one_out(self, t: float, ports: np.ndarray, y: np.ndarray, s: np.ndarray) -> int | None:
        """A gated frame's innovation y (m,) and covariance s (m, m) of `ports`: the port whose
        removal alone makes the frame consistent, once it has been so SUSPECT_FRAMES frames running."""
        m = len(ports)
        nis = np.array([float(y[keep] @ np.linalg.solve(s[np.ix_(keep, keep)], y[keep]))
                        for keep in (np.arange(m) != k for k in range(m))])
        order = np.argsort(nis)
        clear = nis[order[0]] < chi2.ppf(0.999, m - 1) and nis[order[0]] <= AMBIGUITY * nis[order[1]]
        port = int(ports[order[0]]) if clear else None
        if port is None or port != self._suspect:
            self._suspect, self._count = port, 0
        if port is None:
            return None
        self._count += 1
        if self._count >= SUSPECT_FRAMES:
            self.detections.append((t, port))
            self._suspect, self._count = None, 0
            return port
        return None

    def clear(self) -> None:
        """A frame passed the gate: no suspect any more."""
        self._suspect, self._count = None, 0
