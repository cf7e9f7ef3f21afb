"""Seed 003's model-error case in the simulation: a step in deck-flexure intensity and in the
master INS velocity noise at a given time (the filter is not told)."""
import numpy as np
import pytest

from alignment_core.aircraft.deck_flexure import FlexureConfig, FlexureProcess
from alignment_core.samples import ShipBatch
from alignment_core.sensors.master_ins import MasterConfig, MasterInsModel
from alignment_core.units import ARCMIN, DEG
from alignment_core.validation import ConfigError, build


def test_flexure_intensity_step_scales_the_stationary_sigma():
    rate, tau, sigma, factor, t_change = 20.0, 1.0, 3.0, 2.5, 500.0
    cfg = FlexureConfig(enabled=True, sigma_arcmin=sigma, tau_s=tau, static_arcmin=0.0,
                        change_at_s=t_change, change_factor=factor)
    th, _ = FlexureProcess(cfg, 3, rate).generate(int(1000.0 * rate))
    before = th[:int(t_change * rate)] / ARCMIN
    after = th[int((t_change + 20 * tau) * rate):] / ARCMIN      # 20 tau after the step: stationary again
    # about 500 / (2 tau) independent samples per axis and window: std within ~10 %
    assert np.std(before) == pytest.approx(sigma, rel=0.1)
    assert np.std(after) == pytest.approx(factor * sigma, rel=0.1)
    # identical draws before the step as without it
    th0, _ = FlexureProcess(FlexureConfig(enabled=True, sigma_arcmin=sigma, tau_s=tau, static_arcmin=0.0),
                            3, rate).generate(int(t_change * rate))
    np.testing.assert_array_equal(th0, th[:len(th0)])


def _ships(t_ns: np.ndarray) -> ShipBatch:
    n = len(t_ns)
    return ShipBatch(t_ns=t_ns, p_w=np.zeros((n, 3)) + [6.4e6, 0, 0], q_nb=np.tile([0, 0, 0, 1.0], (n, 1)),
                     v_b=np.zeros((n, 3)), w_b=np.zeros((n, 3)), a_b=np.zeros((n, 3)), wdot_b=np.zeros((n, 3)))


def test_master_velocity_noise_step():
    t0 = 1_000_000_000
    t = t0 + np.arange(20000, dtype=np.int64) * 10_000_000             # 200 s at 100 Hz
    cfg = MasterConfig(velocity_noise_mps=0.1, noise_change_at_s=100.0, noise_change_factor=np.sqrt(50.0))
    out = MasterInsModel(cfg, 5, 40 * DEG, t0).measure_batch(_ships(t))
    v = np.array([m.v_b for m in out])
    k = 10000
    # 30000 draws per window: std of the std ~0.4 %
    assert np.std(v[:k]) == pytest.approx(0.1, rel=0.02)
    assert np.std(v[k:]) == pytest.approx(0.1 * np.sqrt(50.0), rel=0.02)


def test_bad_change_parameters_are_named():
    with pytest.raises(ConfigError, match='change_factor'):
        build(FlexureConfig, {'change_factor': -1.0})
    with pytest.raises(ConfigError, match='noise_change_at_s'):
        build(MasterConfig, {'noise_change_at_s': -5.0})
