"""Output rate and latency of a sensor driven by the simulation's sample clock.

A sensor sampled at `rate_hz` (an integer divisor of the scenario rate; 0 = the scenario rate)
measures at the ship samples k = 0, d, 2d, ... (d = scenario rate / sensor rate). Its data
valid at time t are stamped t + latency and released (published) once simulation time has
reached that stamp; data whose stamp falls after the last ship sample are never released.
This is what a filter's delay state must estimate: the stamp is the arrival time, the data
are `latency` older. With a transport jitter J > 0 each sample's delay is latency + U(0, J),
a uniform draw per measured sample (one random stream per sensor), rounded to the nanosecond;
J must be below the sensor's sample interval, so the stamps stay strictly increasing and the
samples arrive in order (mean delay latency + J/2, standard deviation J/sqrt(12)).
The node (one sample at a time) and the batch pipeline (all at once) apply the same rule,
so both release the same samples with the same stamps.
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

    def __init__(self, rate_hz: float, latency_s: float, base_rate_hz: float, t0_ns: int,
                 jitter_s: float = 0.0, jitter_rng: np.random.Generator | None = None) -> None:
        self.every = decimation(rate_hz, base_rate_hz)
        self.base_dt_ns = int(round(1e9 / base_rate_hz))
        self.t0_ns = t0_ns
        self.latency_ns = int(round(latency_s * 1e9))
        self.pending: deque[Any] = deque()
        self.jitter_ns = int(round(jitter_s * 1e9))
        require(self.jitter_ns == 0 or jitter_rng is not None, 'a transport jitter needs its random stream')
        require(self.jitter_ns < self.every * self.base_dt_ns,
                f"latency jitter {jitter_s} s must be below the sample interval "
                f"{self.every * self.base_dt_ns * 1e-9} s (stamps must stay in order)")
        self.jitter_rng = jitter_rng

    def delays_ns(self, n: int) -> np.ndarray:
        """Delays (ns, int64) of the next n measured samples: the latency plus, with a jitter, a
        uniform draw in [0, jitter) each (module docstring); the same numbers one at a time or
        all at once."""
        if not self.jitter_ns:
            return np.full(n, self.latency_ns, dtype=np.int64)
        assert self.jitter_rng is not None
        return self.latency_ns + np.round(self.jitter_rng.random(n) * self.jitter_ns).astype(np.int64)

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
