"""MasterInsStage.step_many (the master node's chunked path) against `step` sample by sample: any
split of a run into chunks gives every master sample and its truth errors bit for bit, in the same
order, with the velocity noise, the jitter stream, the Schuler error state and the latency queue
carried across chunks; and run_batch (the pipeline) releases the same outputs."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import MasterSample, ShipBatch
from alignment_core.sensors.master_ins import MasterInsStage, MasterOutput
from alignment_core.units import DEG

CASES = {
    'constant errors at the scenario rate, no latency': (
        'catapult', {'duration_s': 3.0, 'master.model': 'constant', 'master.rate_hz': 0.0, 'master.latency_s': 0.0,
                     'master.latency_jitter_s': 0.0}),
    'deck: its own master (rate, latency, jitter)': ('deck', {'duration_s': 3.0}),
    'schuler, noise, latency and jitter, own rate': (
        'catapult', {'duration_s': 4.0, 'master.model': 'schuler', 'master.arw_dpsh': 0.01, 'master.vrw_ugpshz': 5.0,
                     'master.rate_hz': 50.0, 'master.latency_s': 0.03, 'master.latency_jitter_s': 0.015}),
    'noise change inside the run': ('deck_paper', {'duration_s': 3.0, 'master.noise_change_at_s': 1.5,
                                                   'master.noise_change_factor': 7.0}),
}
SPLITS = {'irregular': [1, 7, 25, 3, 50, 2, 13, 1, 40], 'node-like': [50]}


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _assert_same(got: list[MasterOutput], want: list[MasterOutput]) -> None:
    assert len(got) == len(want)
    for k, (x, y) in enumerate(zip(got, want)):
        assert x.sample.t_ns == y.sample.t_ns, f'output {k}: stamp'
        for f in MasterSample.__dataclass_fields__:
            if f != 't_ns':
                assert _same(getattr(x.sample, f), getattr(y.sample, f)), f'output {k}: {f} differs'
        assert _same(x.phi, y.phi) and _same(x.dv, y.dv), f'output {k}: truth errors differ'


def _stage(sc: scenario.Scenario) -> MasterInsStage:
    return MasterInsStage(sc.master, sc.seed, sc.ship.lat_deg * DEG, sc.rate_hz, sc.t0_ns)


@pytest.fixture(scope='module', params=list(CASES), ids=list(CASES))
def stepped(request):
    """The scenario, its ship samples and `step`'s outputs (the reference)."""
    name, over = CASES[request.param]
    sc = scenario.load(name, over)
    ships = pipeline.ship_samples(sc)
    stage = _stage(sc)
    ref = [out for s in ships for out in stage.step(s)]
    assert len(ref) > 10
    return sc, ships, ref


@pytest.mark.parametrize('split', list(SPLITS))
def test_chunks_give_the_outputs_of_stepping_bit_for_bit(stepped, split):
    sc, ships, ref = stepped
    stage = _stage(sc)
    got: list[MasterOutput] = []
    k = 0
    for n in itertools.cycle(SPLITS[split]):
        if k >= len(ships):
            break
        got += stage.step_many(ships[k:k + n])
        k += n
    _assert_same(got, ref)
    assert not stage.timing.pending or stage.timing.pending[0].t_ns > ships[-1].t_ns


def test_the_batch_pipeline_gives_the_outputs_of_stepping(stepped):
    sc, ships, ref = stepped
    _assert_same(_stage(sc).run_batch(ShipBatch.of(ships)), ref)


def test_a_chunk_releases_only_what_its_last_sample_has_reached():
    sc = scenario.load('catapult', {'duration_s': 1.0, 'master.rate_hz': 0.0, 'master.latency_s': 0.05,
                                   'master.latency_jitter_s': 0.0})
    ships = pipeline.ship_samples(sc)
    stage = _stage(sc)
    got = stage.step_many(ships[:10])                    # 0.09 s of data: five samples still in transit
    assert [o.t_ns for o in got] == [s.t_ns + 50_000_000 for s in ships[:5]]
    assert len(stage.timing.pending) == 5


def test_an_empty_chunk_gives_nothing():
    sc = scenario.load('catapult', {'duration_s': 1.0})
    assert _stage(sc).step_many([]) == []
