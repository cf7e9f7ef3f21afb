"""Seed 002's Butterworth low-pass (lever_arm_treatment: butterworth): the paper's coefficients,
the closed-form Butterworth magnitude, causal stepping identical to one batch lfilter call, and
the memory shift that follows a closed-loop velocity correction."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.estimation.filters.lowpass import ButterworthLowPass


def test_default_cutoff_gives_the_papers_transfer_function():
    """Seed 002 eq 19-21: G(z) = (2.453e-4 + 4.906e-4 z^-1 + 2.453e-4 z^-2) / (1 - 1.9551 z^-1 + 0.9562 z^-2),
    ~ butter(2, 0.0101) at 100 Hz (0.0101 x 50 Hz = 0.505 Hz, the default). The printed digits are
    rounded and not all from one cut-off (b0 = 2.453e-4 and a2 = 0.9562 fit 0.01008, a1 = -1.9551
    fits 0.0101, which gives b0 = 2.4616e-4, a1 = -1.95513, a2 = 0.95612): 0.4 % on b, 1e-4 on a."""
    f = ButterworthLowPass(0.0101 * 50.0, 100.0)
    np.testing.assert_allclose(f.b, [2.453e-4, 4.906e-4, 2.453e-4], rtol=4e-3)
    np.testing.assert_allclose(f.a, [1.0, -1.9551, 0.9562], rtol=0, atol=1e-4)


@pytest.mark.parametrize('cutoff,rate', [(0.505, 100.0), (2.0, 50.0), (10.0, 200.0)])
def test_dc_gain_is_one_and_minus_3_db_at_the_cutoff(cutoff, rate):
    """Bilinear-transform Butterworth of order N: |H|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2N)):
    1 at DC, 1/2 (-3.01 dB) at fc."""
    f = ButterworthLowPass(cutoff, rate)
    assert abs(f.b.sum() / f.a.sum() - 1.0) < 1e-12
    assert abs(f.gain(0.0) - 1.0) < 1e-12
    assert abs(f.gain(cutoff) ** 2 - 0.5) < 1e-9
    for fr in (0.1 * cutoff, 3.0 * cutoff, 0.45 * rate):
        ratio = np.tan(np.pi * fr / rate) / np.tan(np.pi * cutoff / rate)
        assert abs(f.gain(fr) ** 2 - 1.0 / (1.0 + ratio ** 4)) < 1e-9


def test_stepping_equals_one_batch_call_exactly():
    rng = np.random.default_rng(4)
    xs = np.cumsum(rng.standard_normal((500, 3)), axis=0) * 0.01 + rng.standard_normal((500, 3))
    f = ButterworthLowPass(0.505, 100.0)
    stepped = np.array([f.step(x) for x in xs])
    np.testing.assert_array_equal(stepped, ButterworthLowPass(0.505, 100.0).batch(xs))
    # a constant input passes unchanged from the first sample (it starts in steady state)
    g = ButterworthLowPass(0.505, 100.0)
    np.testing.assert_allclose([g.step(np.array([0.3, -1.0, 2.0])) for _ in range(50)],
                               np.tile([0.3, -1.0, 2.0], (50, 1)), rtol=1e-12)


def test_shift_is_a_constant_added_to_the_whole_history():
    """Filtering x, then shift(c), then x + c afterwards, equals filtering x + c throughout
    (linearity; the filter started in steady state either way)."""
    rng = np.random.default_rng(5)
    xs = rng.standard_normal((300, 3))
    c = np.array([0.5, -0.2, 0.1])
    a = ButterworthLowPass(0.505, 100.0)
    out_a = [a.step(x) for x in xs[:120]]
    a.shift(c)
    out_a += [a.step(x + c) for x in xs[120:]]
    b = ButterworthLowPass(0.505, 100.0)
    out_b = [b.step(x + c) for x in xs]
    np.testing.assert_allclose(np.array(out_a)[120:], np.array(out_b)[120:], rtol=0, atol=1e-12)


def test_cutoff_above_nyquist_is_refused():
    with pytest.raises(ValueError, match='Nyquist'):
        ButterworthLowPass(60.0, 100.0)
