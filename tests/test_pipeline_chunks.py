"""SlaveImuStage.step_many (the slave node's chunked path) against `step` sample by sample: any
split of a run into chunks gives every AircraftTruth, ImuSample and bias row bit for bit, with
the state carried across chunks (the gear's integrator and gusts, the deck flexure, the catapult
release and the flight path, the IMU error model's noise, bias processes and quantiser); and
run_batch (the pipeline, in batches of any size) gives the same numbers as stepping.

Short runs with the events inside: the catapult's hold-back and launch, a free flight after the
papers' stroke, flight segments after a release, an airborne start, and the optional IMU errors."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import AircraftTruth, ImuSample, ShipBatch, ShipSample

IMU_ERRORS = {'aircraft.vibration.enabled': True, 'aircraft.vibration.mode': 'motion',
              'imu.gyro_scale_ppm': 100.0, 'imu.accel_scale_ppm': 100.0, 'imu.gyro_nonorth_arcsec': 10.0,
              'imu.accel_nonorth_arcsec': 10.0, 'imu.gyro_g_sensitivity_dphpg': 1.0,
              'imu.gyro_bias_instability_dph': 0.01, 'imu.accel_bias_instability_ug': 20.0,
              'imu.gyro_bias_rw_dphps': 0.01, 'imu.accel_bias_rw_ugps': 5.0,
              'imu.angle_quantum_arcsec': 0.1, 'imu.velocity_quantum_mps': 1e-4}

CASES = {
    'catapult: hold-back, launch, flight': ('catapult', {'duration_s': 10.0, 'aircraft.catapult.launch_time_s': 4.0}),
    'deck': ('deck', {'duration_s': 3.0}),
    'catapult_paper: stroke, free flight': ('catapult_paper', {'duration_s': 7.0,
                                                               'aircraft.catapult.launch_time_s': 2.0}),
    'seed004: airborne': ('seed004', {'duration_s': 3.0}),
    'carrier_flight: release into segments': ('carrier_flight', {'duration_s': 6.0,
                                                                 'aircraft.catapult.launch_time_s': 1.0}),
    'catapult: every IMU error, vibration': ('catapult', {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 2.0,
                                                          **IMU_ERRORS}),
    'catapult_paper: point samples': ('catapult_paper', {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 2.0,
                                                         'imu.output': 'sample'}),
}

SPLITS = {'irregular': [1, 7, 25, 3, 50, 2, 13, 1, 40], 'node-like': [50], 'pairs': [2]}

Stepped = tuple[list[ShipSample], list[AircraftTruth], list[ImuSample | None], list[np.ndarray | None]]


def _same(a, b) -> bool:
    """Equal values and equal bits (np.array_equal alone takes -0.0 for 0.0)."""
    a, b = np.asarray(a), np.asarray(b)
    return np.array_equal(a, b) and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.fixture(scope='module', params=list(CASES), ids=list(CASES))
def stepped(request) -> tuple[scenario.Scenario, Stepped]:
    """The scenario, its ship samples and `step`'s outputs, sample by sample (the reference)."""
    name, over = CASES[request.param]
    sc = scenario.load(name, over)
    ships = pipeline.ship_samples(sc)
    stage = pipeline.SlaveImuStage(sc)
    truths, imus, biases = [], [], []
    for s in ships:
        truth, imu = stage.step(s)
        truths.append(truth)
        imus.append(imu)
        biases.append(None if imu is None else stage.errors.last_bias[-1].copy())
    on_deck = [t.on_deck for t in truths]
    assert imus[0] is None and all(i is not None for i in imus[1:])
    if 'launch_time_s' in str(over):
        assert on_deck[0] and not on_deck[-1], 'the release must fall inside the run'
    return sc, (ships, truths, imus, biases)


def _assert_truth(a: AircraftTruth, b: AircraftTruth, k: int) -> None:
    for f in AircraftTruth.__slots__:
        assert _same(getattr(a, f), getattr(b, f)), f'sample {k}: truth.{f} differs'


def _assert_imu(a: ImuSample, b: ImuSample, k: int) -> None:
    for f in ImuSample.__slots__:
        assert _same(getattr(a, f), getattr(b, f)), f'sample {k}: imu.{f} differs'


@pytest.mark.parametrize('split', list(SPLITS))
def test_chunks_equal_steps(stepped, split):
    sc, (ships, truths, imus, biases) = stepped
    stage = pipeline.SlaveImuStage(sc)
    sizes = itertools.cycle(SPLITS[split])
    k = 0
    while k < len(ships):
        chunk = ships[k:k + next(sizes)]
        out = stage.step_many(chunk)
        assert len(out) == len(chunk)
        j = 0                                         # row of last_bias: the chunk's IMU samples in order
        for truth, imu in out:
            _assert_truth(truth, truths[k], k)
            if imus[k] is None:
                assert imu is None, f'sample {k}: an IMU sample before the second ship sample'
            else:
                _assert_imu(imu, imus[k], k)
                assert _same(stage.errors.last_bias[j], biases[k]), f'sample {k}: last_bias differs'
                j += 1
            k += 1
        if j:
            assert len(stage.errors.last_bias) == j
        assert stage.prev is chunk[-1]
    assert stage.step_many([]) == []


def test_steps_continue_chunks(stepped):
    """Chunks and single steps mixed on one stage: each continues the other's state."""
    sc, (ships, truths, imus, _) = stepped
    stage = pipeline.SlaveImuStage(sc)
    k = 0
    for n in itertools.cycle([5, 1, 1, 30]):
        if k >= len(ships):
            break
        if n == 1:
            out = [stage.step(ships[k])]
        else:
            out = stage.step_many(ships[k:k + n])
        for truth, imu in out:
            _assert_truth(truth, truths[k], k)
            if imu is not None:
                _assert_imu(imu, imus[k], k)
            k += 1


@pytest.mark.parametrize('batch', [None, 1, 7, 250])
def test_batch_equals_steps(stepped, batch, monkeypatch):
    """The pipeline's run_batch gives the numbers the node's stepping gives, whatever the size of
    the batches it makes (None: its own, longer than these runs)."""
    sc, (ships, truths, imus, biases) = stepped
    if batch is not None:
        monkeypatch.setattr(pipeline, 'BATCH_SAMPLES', batch)
    stage = pipeline.SlaveImuStage(sc)
    truth, imu = stage.run_batch(ShipBatch.of(ships))
    for k, t in enumerate(truths):
        for f in ('p_w', 'q_nb', 'v_b', 'w_b'):
            assert _same(truth[f][k], getattr(t, f)), f'sample {k}: batch {f} differs'
        assert bool(truth['on_deck'][k]) == t.on_deck
    for k in range(1, len(ships)):
        _assert_imu(imu[k - 1], imus[k], k)
        assert _same(stage.errors.last_bias[k - 1], biases[k])
    assert len(imu) == len(stage.errors.last_bias) == len(ships) - 1 and stage.prev is not None


@pytest.mark.parametrize('name', ['deck', 'deck_paper', 'carrier_flight'])
def test_the_ship_in_chunks_of_any_size_is_the_whole_runs(name):
    """The ship's truth evaluated one sample at a time, in chunks of 7 and of the ship node's 100
    gives the whole run's, bit for bit (a single row's world position included: numpy's product of
    one row rounds unlike a matrix's)."""
    sc = scenario.load(name, {'duration_s': 2.0})
    n = 201
    taus = (np.arange(n) * sc.dt_ns) / 1e9
    whole = pipeline.ship_source(sc).sample_batch(taus, sc.t0_ns, sc.dt_ns)
    for chunk in (1, 7, 100):
        src = pipeline.ship_source(sc)
        parts = [src.sample_batch(taus[a:a + chunk], sc.t0_ns, sc.dt_ns, k0=a) for a in range(0, n, chunk)]
        for field in ('p_w', 'q_nb', 'v_b', 'w_b', 'a_b', 'wdot_b'):
            got = np.concatenate([getattr(p, field) for p in parts])
            assert got.tobytes() == getattr(whole, field).tobytes(), (chunk, field)
