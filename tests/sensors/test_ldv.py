"""LDV errors: bias and scale factor recovered by regression on a known velocity profile;
range and speed limits; dropouts occupy the stationary fraction r d / (1 + r d) of the time
(about r d when small) within the tolerance of a two-state Markov process; own rate and
latency, stepping = batch."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.geometry import earth
from alignment_core.samples import AircraftTruth, ShipBatch
from alignment_core.sensors.ldv import LdvConfig, LdvModel, LdvStage

PLANE = earth.TangentPlane(0.7, 2.0, 0.0)
ORIGIN = np.array([40.0, -10.0, 15.0])


def still_ship(n: int, dt_ns: int = 10_000_000, t0_ns: int = 1_000_000_000) -> ShipBatch:
    """A ship at rest at the world origin, level, heading East (ship axes = ENU)."""
    z = np.zeros((n, 3))
    return ShipBatch(t_ns=t0_ns + np.arange(n, dtype=np.int64) * dt_ns, p_w=z.copy(),
                     q_nb=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), v_b=z.copy(), w_b=z.copy(),
                     a_b=z.copy(), wdot_b=z.copy())


def test_bias_and_scale_recovered_by_regression():
    cfg = LdvConfig(noise_mps=0.01, bias_mps=0.05, scale_ppm=2000.0)
    m = LdvModel(cfg, seed=3, plane=PLANE)
    n = 20000
    t = np.arange(n) * 0.01
    v = np.c_[0.3 * t, 2.0 * np.sin(0.5 * t), 1.5 * np.cos(0.3 * t)]   # known profile, m/s
    sb = still_ship(n)
    p = np.tile(ORIGIN, (n, 1))                                           # in the beam
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    out = m.measure_batch(sb, p, q, v)
    z = np.array([s.v_s for s in out])
    assert all(s.valid for s in out)
    for ax in range(3):
        design = np.c_[v[:, ax], np.ones(n)]
        coef, *_ = np.linalg.lstsq(design, z[:, ax], rcond=None)
        cov = cfg.noise_mps**2 * np.linalg.inv(design.T @ design)
        assert coef[0] - 1.0 == pytest.approx(m.scale[ax], abs=4 * np.sqrt(cov[0, 0]))
        assert coef[1] == pytest.approx(m.bias[ax], abs=4 * np.sqrt(cov[1, 1]))
    assert np.max(np.abs(m.scale)) > 1e-4 and np.max(np.abs(m.bias)) > 0.01     # really drawn


def test_range_and_speed_limits():
    cfg = LdvConfig(head_offset_m=-5.0, max_range_m=30.0, max_speed_mps=50.0, track_length_m=95.0)
    m = LdvModel(cfg, seed=1, plane=PLANE)
    along = np.array([0.0, 20.0, 24.9, 25.1, 60.0, 10.0, 10.0])      # m along the track from the spot
    speed = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 49.0, 51.0])
    n = len(along)
    p = ORIGIN + np.c_[along, np.zeros((n, 2))]
    v = np.c_[speed, np.zeros((n, 2))]
    out = m.measure_batch(still_ship(n), p, np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), v)
    # head 5 m behind the spot, 30 m range -> valid up to 25 m along; speed limit 50 m/s
    assert [s.valid for s in out] == [True, True, True, False, False, True, False]
    assert np.all(out[3].v_s == 0.0)


def test_dropout_fraction_and_duration():
    rate, mean = 0.5, 0.2
    cfg = LdvConfig(dropout_rate_hz=rate, dropout_mean_s=mean)
    m = LdvModel(cfg, seed=11, plane=PLANE)
    n, dt = 200_000, 0.01
    out = m.measure_batch(still_ship(n), np.tile(ORIGIN, (n, 1)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
                          np.zeros((n, 3)))
    drop = ~np.array([s.valid for s in out])
    p = rate * mean / (1 + rate * mean)                   # ~ rate x mean duration (0.1) when small
    tau_c = 1.0 / (rate + 1.0 / mean)                      # correlation time of the two-state process
    sd = np.sqrt(2 * p * (1 - p) * tau_c / (n * dt))       # std of a time average over T
    assert np.mean(drop) == pytest.approx(p, abs=4 * sd)
    starts = np.flatnonzero(drop[1:] & ~drop[:-1])
    ends = np.flatnonzero(~drop[1:] & drop[:-1])
    ends = ends[ends > starts[0]][:len(starts) - 1]
    durations = (ends - starts[:len(ends)]) * dt
    assert np.mean(durations) == pytest.approx(mean, rel=4 / np.sqrt(len(durations)) + 0.03)


def test_own_rate_and_latency_step_equals_batch():
    cfg = LdvConfig(rate_hz=25.0, latency_s=0.013, dropout_rate_hz=2.0, dropout_mean_s=0.05, bias_mps=0.01)
    n = 101
    sb = still_ship(n)
    p = np.tile(ORIGIN, (n, 1))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    v = np.c_[np.linspace(0, 5, n), np.zeros((n, 2))]
    batch = LdvStage(cfg, 2, PLANE, 100.0, int(sb.t_ns[0])).run_batch(sb, p, q, v)
    st = LdvStage(cfg, 2, PLANE, 100.0, int(sb.t_ns[0]))
    stepped = []
    for k in range(n):
        a = AircraftTruth(t_ns=int(sb.t_ns[k]), p_w=p[k], q_nb=q[k], v_b=v[k], w_b=np.zeros(3),
                          misalignment=np.zeros(3), on_deck=True)
        stepped += st.step(sb.sample(k), a)
    # measured at 0, 40, ..., 1000 ms (26 samples), stamped 13 ms later; the last is past the end
    want = [int(sb.t_ns[0]) + k * 40_000_000 + 13_000_000 for k in range(25)]
    assert [s.t_ns for s in batch] == want == [s.t_ns for s in stepped]
    assert [s.valid for s in batch] == [s.valid for s in stepped]
    np.testing.assert_allclose([s.v_s for s in batch], [s.v_s for s in stepped], rtol=0, atol=1e-12)
