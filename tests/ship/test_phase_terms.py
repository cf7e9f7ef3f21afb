"""The wave components' phase factors (ship/phase_terms.py): the compiled pass gives the bits of
numpy's form of the same arithmetic, and of its own interpreted form, at the phases a long run
reaches; the factors are those of e^{i phi}, i phi' e^{i phi} and (i phi'' - phi'^2) e^{i phi}."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.ship import spectral
from alignment_core.ship.phase_terms import phase_terms


def _numpy_form(ph, pd, pdd):
    cs, sn = np.cos(ph), np.sin(ph)
    spd, cpd = sn * pd, cs * pd
    return cs, sn, spd, cpd, sn * pdd - cpd * pd, -(cs * pdd + spd * pd)


def _inputs(n=37, m=211, scale=1e4):
    rng = np.random.default_rng(11)
    ph = (rng.random((n, m)) - 0.5) * scale             # a run's phases grow to thousands of rad
    ph[0, :4] = (0.0, -0.0, np.pi, 1e6)
    ph[1, :3] = (np.nan, np.inf, -np.inf)                # numpy's NaNs (their bits too)
    return ph, rng.normal(size=(n, m)), rng.normal(size=(n, m)) * 0.1


def _run(fun, ph, pd, pdd):
    out = np.full((6,) + ph.shape, np.nan)
    fun(ph, pd, pdd, *out)
    return out


@pytest.mark.filterwarnings('ignore:invalid value encountered:RuntimeWarning')
def test_the_compiled_pass_gives_numpys_bits_and_its_own_interpreted_ones():
    ph, pd, pdd = _inputs()
    compiled = _run(phase_terms, ph, pd, pdd)
    for name, got, want in zip(('cos', 'sin', 'sin pd', 'cos pd', 'Re G', 'Im G'), compiled,
                               _numpy_form(ph, pd, pdd)):
        assert got.tobytes() == want.tobytes(), name
    assert compiled.tobytes() == _run(phase_terms.py_func, ph, pd, pdd).tobytes()


def test_the_factors_are_those_of_the_complex_exponential_and_its_derivatives():
    """Independent of the code: Z = e^{i phi}; d/dt (Z W) = i phi' Z W; d2/dt2 = (i phi'' - phi'^2) Z W."""
    ph, pd, pdd = _inputs(5, 7, 20.0)
    ph[~np.isfinite(ph)] = 0.5
    cs, sn, spd, cpd, gr, gi = _run(phase_terms, ph, pd, pdd)
    z = np.exp(1j * ph)
    np.testing.assert_allclose(cs + 1j * sn, z, rtol=0, atol=1e-15)
    np.testing.assert_allclose(-spd + 1j * cpd, 1j * pd * z, rtol=0, atol=1e-14)
    np.testing.assert_allclose(gr + 1j * gi, (1j * -pdd - pd**2) * z, rtol=0, atol=1e-13)


def _numpy_terms(ph, pd, pdd, *out):
    for o, v in zip(out, _numpy_form(ph, pd, pdd)):
        o[...] = np.broadcast_to(v, o.shape)


@pytest.mark.parametrize('n', [1, 255, 257, 700])
def test_the_sea_on_its_track_is_numpys_whatever_the_chunks(monkeypatch, n):
    """WaveFrequencyOnTrack.evaluate with the kernel against numpy's form of its factors, over a
    last chunk shorter than the others, and kinematics of one row for every time of a chunk."""
    sc = scenario.load('deck', {}, seed=2)
    wf = pipeline.ship_source(sc).wf
    assert isinstance(wf, spectral.WaveFrequencyOnTrack)
    t = 3.0 + 0.013 * np.arange(n)
    one = {k: v[:1] for k, v in wf.track.kinematics(t[:1]).items()}
    short = t[:wf.CHUNK]                      # one row broadcasts over one chunk (as numpy's form did)
    got = [wf.evaluate(t), wf.evaluate(short, one)]
    monkeypatch.setattr(spectral, 'phase_terms', _numpy_terms)
    want = [wf.evaluate(t), wf.evaluate(short, one)]
    for g, w in zip(got, want):
        assert g.shape[1] == 19 and g.tobytes() == w.tobytes()
