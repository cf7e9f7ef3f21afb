"""Port fault detection from the filter's innovations: each port's normalised innovation squared
(y_i^2 / S_ii, chi-square with 1 degree of freedom when the port is healthy) averaged over a
sliding window; the worst port whose average exceeds the threshold (over at least MIN_SAMPLES
frames) is declared failed."""
from __future__ import annotations

from collections import deque

import numpy as np

MIN_SAMPLES = 5      # mean of 5 chi2(1) > 9 is chi2(5) > 45: probability 1.5e-8 per test for a healthy port


class PortFaultDetector:
    def __init__(self, n_ports: int, window_s: float, threshold: float) -> None:
        self.window_s, self.threshold = float(window_s), float(threshold)
        self._hist: list[deque[tuple[float, float]]] = [deque() for _ in range(n_ports)]
        self.detections: list[tuple[float, int]] = []

    def add(self, t: float, ports: np.ndarray, normalised: np.ndarray) -> int | None:
        """Record one frame's normalised innovations of `ports`; the port declared failed, or None."""
        worst, worst_mean = None, self.threshold
        for i, v in zip(ports.tolist(), normalised.tolist()):
            h = self._hist[i]
            h.append((t, v))
            while len(h) > MIN_SAMPLES and t - h[0][0] > self.window_s:
                h.popleft()
            if len(h) >= MIN_SAMPLES:
                mean = sum(x for _, x in h) / len(h)
                if mean > worst_mean:
                    worst, worst_mean = i, mean
        if worst is not None:
            self.detections.append((t, worst))
            self._hist[worst].clear()
        return worst
