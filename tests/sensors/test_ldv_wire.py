"""The LDV sample through its message's encoding (sensors/ldv_wire.py): a beam's line of sight
and sigma come back from its rank-1 covariance, a vector LDV's sigma from its diagonal, an
invalid sample stays invalid; the whole-stream form gives the bits the per-sample one does."""
from __future__ import annotations

import math

import numpy as np
import pytest

from alignment_core.samples import LdvSample
from alignment_core.sensors import ldv_wire


def _samples(n: int = 400) -> list[LdvSample]:
    rng = np.random.default_rng(7)
    out = []
    for k in range(n):
        kind = k % 5
        v = rng.normal(size=3)
        sigma = float(rng.uniform(1e-4, 0.05))
        if kind == 0:
            out.append(LdvSample(t_ns=k, v_s=v, sigma=math.nan, valid=False))
        elif kind == 1:
            out.append(LdvSample(t_ns=k, v_s=v, sigma=sigma, valid=True))
        else:
            u = rng.normal(size=3)
            u /= np.linalg.norm(u)
            out.append(LdvSample(t_ns=k, v_s=float(u @ v) * u, sigma=sigma, valid=True, beam=u))
    return out


def test_a_beam_comes_back_as_its_line_of_sight_and_sigma():
    u = np.array([0.6, -0.48, 0.64])
    s = LdvSample(t_ns=5, v_s=1.5 * u, sigma=0.02, valid=True, beam=u)
    back = ldv_wire.transmitted(s)
    assert back.valid and back.t_ns == 5
    assert math.isclose(back.sigma, 0.02, rel_tol=1e-12)
    # the same line up to its sign (immaterial: the measurement is a projection)
    assert abs(abs(float(back.beam @ u)) - 1.0) < 1e-12
    np.testing.assert_array_equal(back.v_s, s.v_s)
    vector = ldv_wire.transmitted(LdvSample(t_ns=6, v_s=u, sigma=0.03, valid=True))
    assert vector.beam is None and math.isclose(vector.sigma, 0.03, rel_tol=1e-15)
    assert not ldv_wire.transmitted(LdvSample(t_ns=7, v_s=u, sigma=math.nan, valid=False)).valid


def _decoded_alone(s: LdvSample) -> LdvSample:
    """The sample through its wire form, its covariance decomposed on its own (one 3x3 eigh)."""
    v, cov = ldv_wire.encode(s)
    if not cov[0, 0] >= 0.0:
        return LdvSample(t_ns=s.t_ns, v_s=v, sigma=math.nan, valid=False)
    trace = float(np.trace(cov))
    if not np.all(np.isfinite(cov)):
        return LdvSample(t_ns=s.t_ns, v_s=v, sigma=math.sqrt(cov[0, 0]), valid=True)
    w, vec = np.linalg.eigh(0.5 * (cov + cov.T))
    if trace > 0.0 and w[1] <= ldv_wire.BEAM_RANK_TOLERANCE * trace:
        return LdvSample(t_ns=s.t_ns, v_s=v, sigma=math.sqrt(trace), valid=True, beam=vec[:, 2])
    return LdvSample(t_ns=s.t_ns, v_s=v, sigma=math.sqrt(cov[0, 0]), valid=True)


def _same_bits(a: LdvSample, b: LdvSample) -> None:
    assert (a.t_ns, a.valid) == (b.t_ns, b.valid)
    assert a.v_s.tobytes() == b.v_s.tobytes()
    assert np.float64(a.sigma).tobytes() == np.float64(b.sigma).tobytes()
    assert (a.beam is None) == (b.beam is None)
    if a.beam is not None:
        assert a.beam.tobytes() == b.beam.tobytes()


def test_a_stream_decodes_to_the_bits_of_each_matrix_decomposed_alone():
    samples = _samples()
    u = np.array([0.6, -0.48, 0.64])
    for stream in ([], samples[:3]):    # a covariance that is not finite: decomposed by none
        mixed = stream + [LdvSample(t_ns=-1, v_s=u, sigma=math.inf, valid=True, beam=u),
                          LdvSample(t_ns=-2, v_s=u, sigma=math.inf, valid=True)]
        for a, s in zip(ldv_wire.transmitted_all(mixed), mixed):
            _same_bits(a, _decoded_alone(s))
    stream = ldv_wire.transmitted_all(samples)
    assert len(stream) == len(samples)
    for a, s in zip(stream, samples):
        _same_bits(a, _decoded_alone(s))
        _same_bits(ldv_wire.transmitted(s), _decoded_alone(s))
    assert sum(s.beam is not None for s in stream) == 240
    assert sum(not s.valid for s in stream) == 80
    assert ldv_wire.transmitted_all([]) == []
    for batch in (1, 7, len(samples), 10 * len(samples)):   # the batch pipeline's stream, batch by batch
        streamed = list(ldv_wire.transmitted_stream(samples, batch))
        assert len(streamed) == len(samples)
        for a, b in zip(streamed, stream):
            _same_bits(a, b)
    assert list(ldv_wire.transmitted_stream([], 7)) == []


NOT_DECOMPOSABLE = [np.array([[0.0, 1e-9, 1.7e308], [1e-9, 0.0, 1e-300], [1.7e308, 1e-300, 0.0]]),
                    np.array([[-1.0, 0.0, 1.7e308], [0.0, 0.0, 1e-9], [1.7e308, 1e-9, 0.0]]),
                    np.array([[1.0, 0.0, 1.7e308], [0.0, 0.0, 0.0], [1.7e308, 0.0, 0.0]])]
"""Finite covariances whose eigen-decomposition LAPACK does not converge on (numpy raises)."""


@pytest.mark.filterwarnings('ignore:overflow encountered:RuntimeWarning')
def test_a_covariance_that_cannot_be_decomposed_is_not_a_beam_and_stops_nothing():
    """A message whose covariance LAPACK cannot decompose (cells near the end of the float range)
    is read as no beam, alone or in a stack, and the stack's other samples decode as they do
    alone (such a message once raised out of the filter node's callback)."""
    for c in NOT_DECOMPOSABLE:
        with pytest.raises(np.linalg.LinAlgError):
            np.linalg.eigh(0.5 * (c + c.T))
    u = np.array([0.6, -0.48, 0.64])
    good = ldv_wire.encode(LdvSample(t_ns=0, v_s=u, sigma=0.02, valid=True, beam=u))[1]
    covs = [good, *NOT_DECOMPOSABLE, good]
    stack = ldv_wire.decode_all(list(range(len(covs))), np.tile(u, (len(covs), 1)), np.array(covs))
    assert [s.beam is not None for s in stack] == [True, False, False, False, True]
    assert [s.valid for s in stack] == [True, True, False, True, True]
    alone = ldv_wire.decode(0, u, good)
    for s in (stack[0], stack[-1]):
        assert s.beam.tobytes() == alone.beam.tobytes() and s.sigma == alone.sigma


@pytest.mark.filterwarnings('ignore:overflow encountered:RuntimeWarning')
def test_one_message_decodes_to_the_bits_of_the_stack_whatever_its_covariance():
    """The filter node decodes each message alone (decode), the batch pipeline stacks them
    (decode_all): the same sample for any covariance a publisher may send (asymmetric, rank 2,
    zero or negative trace, NaN or inf cells, a negative first cell) as for the LDV's own."""
    rng = np.random.default_rng(3)
    covs = []
    for s in _samples(100):
        covs.append(ldv_wire.encode(s)[1])
    for _ in range(300):
        c = rng.normal(size=(3, 3)) * 10.0 ** rng.integers(-6, 3)
        kind = rng.integers(6)
        if kind == 1:
            u = rng.normal(size=(3, 2))
            c = u @ u.T                                  # rank 2
        elif kind == 2:
            c[rng.integers(3), rng.integers(3)] = rng.choice([np.nan, np.inf, -np.inf])
        elif kind == 3:
            c = -np.abs(c)
        elif kind == 4:
            u = rng.normal(size=3)
            c = np.outer(u, u) * (1.0 + 1e-12 * rng.normal(size=(3, 3)))   # a beam, perturbed
        covs.append(c)
    covs.append(np.zeros((3, 3)))
    covs += NOT_DECOMPOSABLE + [np.diag([1e308, 1e308, 1e308]), np.full((3, 3), 1e308)]   # a trace beyond the range
    linear = rng.normal(size=(len(covs), 3))
    stack = ldv_wire.decode_all(list(range(len(covs))), linear, np.array(covs))
    for k, (v, c, want) in enumerate(zip(linear, covs, stack)):
        _same_bits(ldv_wire.decode(k, v, c), want)
    kinds = [(s.valid, s.beam is not None) for s in stack]
    assert kinds.count((False, False)) > 50 and kinds.count((True, True)) > 100 and kinds.count((True, False)) > 50


def test_the_stack_encodes_to_the_bits_of_each_sample_encoded_alone():
    """encode_all against encode, sample by sample, over invalid, vector and beam samples, with
    sigmas whose square the C library's pow rounds away from sigma * sigma (encode's sigma**2)."""
    samples = _samples()
    draws = np.random.default_rng(3).uniform(1e-4, 0.05, 100_000).tolist()
    odd = [s for s in draws if s**2 != s * s][:4]
    assert len(odd) == 4                      # the case exists on this machine's C library
    u = np.array([0.6, -0.48, 0.64])
    samples += [LdvSample(t_ns=-1, v_s=u, sigma=odd[0], valid=True),
                LdvSample(t_ns=-2, v_s=u, sigma=odd[1], valid=True, beam=u),
                LdvSample(t_ns=-3, v_s=[1.0, 2.0, 3.0], sigma=odd[2], valid=True, beam=list(u)),
                LdvSample(t_ns=-4, v_s=u * math.nan, sigma=odd[3], valid=False, beam=u)]
    linear, cov = ldv_wire.encode_all(samples)
    assert linear.shape == (len(samples), 3) and cov.shape == (len(samples), 3, 3)
    for k, s in enumerate(samples):
        lin1, cov1 = ldv_wire.encode(s)
        assert linear[k].tobytes() == lin1.tobytes() and cov[k].tobytes() == cov1.tobytes(), k
    for batch in (samples[:1], samples[1:2], samples[2:3]):     # one kind alone
        lin_b, cov_b = ldv_wire.encode_all(batch)
        assert cov_b.tobytes() == ldv_wire.encode(batch[0])[1].tobytes()
    empty_lin, empty_cov = ldv_wire.encode_all([])
    assert empty_lin.shape == (0, 3) and empty_cov.shape == (0, 3, 3)


@pytest.mark.parametrize('var', [5e-324, 1e-300, 1e-20, 1e-4, 1.0, 1e20, 1e300])
def test_a_vector_ldvs_covariance_is_no_beam_at_any_scale(var):
    """sigma^2 I is read as a vector sample of sigma without solving for its eigenvalues: numpy's
    eigh of it says the same (its middle eigenvalue is far above the beam's fraction of the
    trace, or it does not converge, which reads as no beam too), alone and in a stack."""
    c = np.eye(3) * var
    try:
        w = np.linalg.eigh(c)[0]
        assert not w[1] <= ldv_wire.BEAM_RANK_TOLERANCE * (3.0 * var)
    except np.linalg.LinAlgError:
        pass
    u = np.array([0.6, -0.48, 0.64])
    beam = ldv_wire.encode(LdvSample(t_ns=0, v_s=u, sigma=0.02, valid=True, beam=u))[1]
    alone = ldv_wire.decode(0, u, c)
    stack = ldv_wire.decode_all([0, 1], np.tile(u, (2, 1)), np.array([c, beam]))
    for s in (alone, stack[0]):
        assert s.valid and s.beam is None and s.sigma == math.sqrt(var)
    assert stack[1].beam is not None
