"""Aligning on the deck with a beam LDV (ldv.mode: beam, filter.ldv_mode follows it): one velocity
row along the line of sight per master sample (models/beam.py) instead of three. The filter
stays consistent; what it sees changes with the beam's direction: a tilt shows up in the
horizontal velocity (f x phi, f ~ g up), so a beam along the ship's x sees pitch directly and
roll only as the ship's motion turns the beam; a vertical beam sees almost no heading (heading
needs horizontal velocity differences)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.health import WARN
from alignment_core.units import ARCMIN
from alignment_core.validation import ConfigError

VERTICAL = {'ldv.mode': 'beam', 'ldv.mount_m': [40.0, -10.0, 35.0], 'ldv.reflector_axis': [0.0, 0.0, 1.0]}


def _deck(extra: dict, seconds: float = 90.0, seed: int = 1):
    sc = scenario.load('deck_paper', {'duration_s': seconds, **extra}, seed=seed)
    res = pipeline.run(sc, keep_truth=False)
    e = res.estimates[-1]
    return sc, res, (e.misalignment - np.array(sc.aircraft.misalignment_arcmin) * ARCMIN), e.misalignment_sigma


def test_beam_along_the_deck_aligns_consistently_and_sees_roll_least():
    sc, res, err, sig = _deck({'ldv.mode': 'beam'})
    assert sc.filter.ldv_mode == 'beam' and res.filter.counters.updates == 9000
    assert np.all(np.abs(err) < 3.0 * sig)
    _, _, _, sig_vector = _deck({})
    # one row instead of three: every axis less well seen; roll (about the beam) the least
    assert np.all(sig > 2.0 * sig_vector)
    assert sig[0] > 5.0 * sig_vector[0] and sig[0] > sig[1]


def test_a_vertical_beam_loses_the_heading():
    sc, res, err, sig = _deck(VERTICAL)
    assert np.all(np.abs(err) < 3.0 * sig)
    assert sig[2] > 10.0 * max(sig[0], sig[1]) and sig[2] > 5.0 * ARCMIN


def test_a_beam_sample_for_a_vector_filter_is_rejected_and_counted():
    """A filter told ldv_mode vector fed a beam LDV (a scenario refuses the contradiction; a node's
    parameters or a recording may still bring it): its samples would be read as full velocity
    vectors (wrong); they are rejected as `ldv_mode`, nothing is matched (relative velocity
    `ldv`: under `auto` a stream with no usable sample is taken as absent and matched as parked)."""
    sc = scenario.load('deck_paper', {'duration_s': 2.0, 'ldv.mode': 'beam', 'filter.relative_velocity': 'ldv'})
    inp = pipeline.simulate(sc)
    f = pipeline.align(replace(sc, filter=replace(sc.filter, ldv_mode='vector')), inp)
    c = f.counters
    assert c.rejected_ldv_mode == 201 and c.ldv == 0 and c.updates == 0
    assert f.status()[0] >= WARN


def test_beam_needs_a_model_with_three_velocity_rows():
    with pytest.raises(ConfigError, match='ldv_mode beam'):
        scenario.load('deck_paper', {'ldv.mode': 'beam', 'filter.model': 'seed002_10'})
