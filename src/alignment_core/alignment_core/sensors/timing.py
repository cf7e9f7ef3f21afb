"""Output rate and latency of a sensor driven by the simulation's sample clock.

A sensor sampled at `rate_hz` (an integer divisor of the scenario rate; 0 = the scenario rate)
measures at the ship samples k = 0, d, 2d, ... (d = scenario rate / sensor rate). Its data
valid at time t are stamped t + latency and released (published) once simulation time has
reached that stamp; data whose stamp falls after the last ship sample are never released.
This is what a filter's delay state must estimate: the stamp is the arrival time, the data
are `latency` older. The node (one sample at a time) and the batch pipeline (all at once)
apply the same rule, so both release the same samples with the same stamps.
"""
from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

from alignment_core.validation import require


def decimation(sensor_rate_hz: float, base_rate_hz: float) -> int:
    """Ship samples per sensor sample (1 when sensor_rate_hz is 0: the scenario rate)."""
    if sensor_rate_hz <= 0.0:
        return 1
    return int(round(base_rate_hz / sensor_rate_hz))


def check_rate(name: str, sensor_rate_hz: float, base_rate_hz: float) -> None:
    """The sensor rate must be 0 (= scenario rate) or divide the scenario rate."""
    if sensor_rate_hz <= 0.0:
        return
    ratio = base_rate_hz / sensor_rate_hz
    require(sensor_rate_hz <= base_rate_hz and abs(ratio - round(ratio)) < 1e-9,
            f"{name} = {sensor_rate_hz} Hz must divide the scenario rate {base_rate_hz} Hz "
            f"(or be 0 for the scenario rate)")


class SensorTiming:
    """Which ship samples a sensor measures at, and when its samples are released."""

    def __init__(self, rate_hz: float, latency_s: float, base_rate_hz: float, t0_ns: int) -> None:
        self.every = decimation(rate_hz, base_rate_hz)
        self.base_dt_ns = int(round(1e9 / base_rate_hz))
        self.t0_ns = t0_ns
        self.latency_ns = int(round(latency_s * 1e9))
        self.pending: deque[Any] = deque()

    def due(self, t_ns: int) -> bool:
        """True if the sensor measures at the ship sample stamped t_ns."""
        k = (t_ns - self.t0_ns) // self.base_dt_ns
        return k % self.every == 0

    def due_mask(self, t_ns: np.ndarray) -> np.ndarray:
        k = (np.asarray(t_ns, dtype=np.int64) - self.t0_ns) // self.base_dt_ns
        return k % self.every == 0

    def stamp(self, t_ns: int) -> int:
        """Stamp of data valid at t_ns."""
        return int(t_ns) + self.latency_ns

    def release(self, now_ns: int, new: list | tuple = ()) -> list:
        """Queue `new` samples (already stamped) and return those whose stamp <= now_ns."""
        self.pending.extend(new)
        out = []
        while self.pending and self.pending[0].t_ns <= now_ns:
            out.append(self.pending.popleft())
        return out

    def release_batch(self, samples: list, t_end_ns: int) -> list:
        """Batch equivalent of `release` over a whole run ending at t_end_ns."""
        return [s for s in samples if s.t_ns <= t_end_ns]
