"""Run-out: how far the simulation of a node graph runs on past the scenario's end so that every
stream covers it.

A graph run ends when every stream of its end topics has a message stamped at or after
t_end = start_time_s + duration_s. The IMU and the truth are stamped at every scenario sample,
so they reach t_end; a sensor with its own rate, latency or jitter (master INS, LDV, Doppler
radar; sensors/timing.py) stamps on its own grid, and its last stamp at or before t_end can
fall short of it. The filter releases events in stamp order once every input stream has passed
them (navigation/ordering.py) and emits at master stamps on its output grid
(estimation/engine.py), so its outputs can fall short too. The batch pipeline flushes at t_end;
a graph cannot tell the last message from a late one, so the simulation runs on instead, for

    run_out = T_out + T + sum over the sensor streams s of (T_s + J_s),

rounded up to whole scenario samples (T_out: output period, T: scenario sample period, T_s:
stream s's sample period, J_s: its jitter). Derivation: the filter's output grid has a point in
[t_end, t_end + T_out); the first master stamp at or after it comes within T_m + J_m (the
latency shifts the stamp grid; it is not a gap); its release needs the IMU (one scenario
sample) and the other sensor streams (T_s + J_s each) to have a stamp at or after it. A stream
that loses samples at the end (an injected fault) is not covered.

The run-out is 0 when every stream lands on t_end (no jitter, t_end on each sensor's stamp grid
and on the output grid), as in the default scenario. Each node is causal in stamp order, so
everything stamped up to t_end is the same with or without the run-out: the batch pipeline
(no run-out) equals the graph there, and what the graph publishes after t_end is recorded but
neither scored nor judged.
"""
from __future__ import annotations

import math

from alignment_core.config.scenario import Scenario
from alignment_core.sensors.timing import decimation


def end_ns(sc: Scenario) -> int:
    """Stamp of the scenario's last sample (t_end, ns)."""
    return sc.t0_ns + (sc.n_samples - 1) * sc.dt_ns


def _sensor_timings(sc: Scenario) -> list[tuple[int, int, int]]:
    """(period, latency, jitter) in ns of the master INS, the LDV and, when enabled, the Doppler radar."""
    out = []
    for cfg in (sc.master, sc.ldv, *((sc.doppler,) if sc.doppler.enabled else ())):
        period = decimation(cfg.rate_hz, sc.rate_hz) * sc.dt_ns
        jitter = round(getattr(cfg, 'latency_jitter_s', 0.0) * 1e9)
        out.append((period, round(cfg.latency_s * 1e9), jitter))
    return out


def _lands(sc: Scenario) -> bool:
    """True if every sensor stream and the filter's output grid have a stamp exactly at t_end."""
    span = end_ns(sc) - sc.t0_ns
    timings = _sensor_timings(sc)
    for period, latency, jitter in timings:
        if jitter or span < latency or (span - latency) % period:
            return False
    master_period, master_latency, _ = timings[0]
    out_period = round(1e9 / sc.filter.output_rate_hz)
    # the first output is at the first master stamp (t0 + latency), then every output period
    return out_period % master_period == 0 and (span - master_latency) % out_period == 0


def run_out_samples(sc: Scenario) -> int:
    """Scenario samples simulated after t_end (module docstring): 0 when every stream lands on it."""
    if _lands(sc):
        return 0
    ns = round(1e9 / sc.filter.output_rate_hz) + sc.dt_ns + sum(p + j for p, _, j in _sensor_timings(sc))
    return math.ceil(ns / sc.dt_ns)


def simulated_samples(sc: Scenario) -> int:
    """Scenario samples a graph run simulates: the scenario's, then the run-out."""
    return sc.n_samples + run_out_samples(sc)
