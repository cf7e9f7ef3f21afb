"""LdvStage.step_many (the LDV node's chunked path) against `step` pair by pair: any split of a
run into chunks gives every LdvSample bit for bit (stamps, validity, velocity, line of sight),
with the noise stream, the dropout process and the latency queue carried across chunks; and
run_batch (the pipeline) releases the same samples. Short runs with the events inside: the beam
losing the reflector at the launch, the vector LDV of the papers, dropouts and sensor errors."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import LdvSample, ShipBatch
from alignment_core.sensors.ldv import LdvStage

CASES = {
    'deck: beam on the gear': ('deck', {'duration_s': 4.0}),
    'catapult: beam through the launch': ('catapult', {'duration_s': 9.0, 'aircraft.catapult.launch_time_s': 3.0}),
    'deck_paper: vector': ('deck_paper', {'duration_s': 3.0}),
    'catapult: dropouts, errors, latency, own rate': (
        'catapult', {'duration_s': 6.0, 'ldv.dropout_rate_hz': 2.0, 'ldv.bias_mps': 0.01, 'ldv.scale_ppm': 100.0,
                     'ldv.latency_s': 0.03, 'ldv.rate_hz': 50.0}),
}
SPLITS = {'irregular': [1, 7, 25, 3, 50, 2, 13, 1, 40], 'node-like': [50]}


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _assert_same(got: list[LdvSample], want: list[LdvSample]) -> None:
    assert len(got) == len(want)
    for k, (x, y) in enumerate(zip(got, want)):
        assert (x.t_ns, x.valid, x.sigma) == (y.t_ns, y.valid, y.sigma), f'sample {k}'
        assert _same(x.v_s, y.v_s), f'sample {k}: v_s differs'
        assert (x.beam is None) == (y.beam is None) and (x.beam is None or _same(x.beam, y.beam)), f'sample {k}: beam'


@pytest.fixture(scope='module', params=list(CASES), ids=list(CASES))
def stepped(request):
    """The scenario, its ship samples, the aircraft truth and `step`'s LDV samples (the reference)."""
    name, over = CASES[request.param]
    sc = scenario.load(name, over)
    ships = pipeline.ship_samples(sc)
    slave = pipeline.SlaveImuStage(sc)
    truths = [slave.step(s)[0] for s in ships]
    stage = LdvStage(sc.ldv, sc.seed, pipeline.plane_of(sc), sc.rate_hz, sc.t0_ns)
    ref = [x for s, t in zip(ships, truths) for x in stage.step(s, t)]
    assert any(x.valid for x in ref)
    return sc, ships, truths, ref


@pytest.mark.parametrize('split', list(SPLITS))
def test_chunks_give_the_samples_of_stepping_bit_for_bit(stepped, split):
    sc, ships, truths, ref = stepped
    stage = LdvStage(sc.ldv, sc.seed, pipeline.plane_of(sc), sc.rate_hz, sc.t0_ns)
    got: list[LdvSample] = []
    k = 0
    for n in itertools.cycle(SPLITS[split]):
        if k >= len(ships):
            break
        got += stage.step_many(ships[k:k + n], truths[k:k + n])
        k += n
    _assert_same(got, ref)


def test_the_batch_pipeline_gives_the_samples_of_stepping(stepped):
    sc, ships, truths, ref = stepped
    stage = LdvStage(sc.ldv, sc.seed, pipeline.plane_of(sc), sc.rate_hz, sc.t0_ns)
    got = stage.run_batch(ShipBatch.of(ships), np.array([t.p_w for t in truths]), np.array([t.q_nb for t in truths]),
                          np.array([t.v_b for t in truths]), np.array([t.w_b for t in truths]))
    _assert_same(got, ref)


def test_an_empty_chunk_gives_nothing(stepped):
    sc, *_ = stepped
    assert LdvStage(sc.ldv, sc.seed, pipeline.plane_of(sc), sc.rate_hz, sc.t0_ns).step_many([], []) == []
