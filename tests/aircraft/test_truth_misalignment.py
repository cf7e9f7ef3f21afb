"""The truth misalignment (/truth/misalignment, the experiments' score) is the IMU axes relative
to the master's at each sample: on a rigid deck exactly the configured mounting; on the gear and
a flexing deck it moves, and the graph's per-sample path gives the batch's numbers."""
from __future__ import annotations

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.units import ARCMIN
from alignment_experiments.monte_carlo import true_misalignment


def test_on_a_rigid_deck_the_truth_is_the_mounting():
    sc = scenario.load('catapult_paper', {'duration_s': 3.0}, seed=3)
    r = pipeline.run(sc)
    mu = np.array([t.misalignment for t in r.truth if t.on_deck])
    expected = np.array(sc.aircraft.misalignment_arcmin) * ARCMIN          # the scenario's mounting
    assert len(mu) == len(r.truth)
    assert np.max(np.abs(mu - expected)) < 1e-12


def test_on_the_gear_the_truth_moves_and_the_per_sample_path_matches_the_batch():
    sc = scenario.load('deck', {'duration_s': 8.0}, seed=1)
    inp = pipeline.simulate(sc)
    batch = true_misalignment(inp)
    stage = pipeline.SlaveImuStage(sc)
    per_sample = np.array([stage.step(inp.ships.sample(k))[0].misalignment for k in range(len(inp.ships))])
    assert np.max(np.abs(per_sample - batch)) < 1e-12
    assert np.min(np.std(batch, axis=0)) > 0.5 * ARCMIN                  # gear and flexure: arcminutes
    mounting = np.array(sc.aircraft.misalignment_arcmin) * ARCMIN
    assert np.max(np.abs(np.mean(batch, axis=0) - mounting)) < 10 * ARCMIN
