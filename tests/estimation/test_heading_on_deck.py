"""An aircraft turned on the deck (aircraft.heading_on_deck_deg, e.g. a waist catapult at -9 deg):
the filter starts the slave from the master attitude turned by the nominal heading and reports
the misalignment relative to that nominal mounting; the LDV beam runs along the catapult track."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.units import ARCMIN

SHORT = {'duration_s': 12.0, 'aircraft.catapult.launch_time_s': 8.0}
SEEDS = (1, 2, 3)


def _errors(**ov):
    out = []
    for seed in SEEDS:
        sc = scenario.load('catapult_paper', {**SHORT, **ov}, seed=seed)
        res = pipeline.run(sc, keep_truth=False)
        e = res.estimates[-1]
        mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
        out.append((e.misalignment - mu, e.misalignment_sigma, res.filter.counters.updates))
    return out


@pytest.fixture(scope='module')
def bow():
    return _errors()


def test_the_scenario_gives_the_filter_and_the_ldv_the_heading():
    sc = scenario.load('catapult_paper', {'aircraft.heading_on_deck_deg': -9.0})
    assert sc.filter.heading_on_deck_deg == -9.0 and sc.ldv.track_heading_deg == -9.0
    sc = scenario.load('catapult_paper', {'aircraft.heading_on_deck_deg': -9.0, 'filter.heading_on_deck_deg': -8.0})
    assert sc.filter.heading_on_deck_deg == -8.0


def test_heading_minus_9_deg_aligns_as_well_as_a_bow_catapult(bow):
    """The heading on deck is a known rotation of the nominal mounting about the deck normal: it
    turns the stroke's specific force in the ship frame but not in the aircraft's, so nothing
    about the observability changes and the accuracy (error, sigma, number of updates) is
    the bow catapult's, the same seeds giving errors of the same size."""
    waist = _errors(**{'aircraft.heading_on_deck_deg': -9.0})
    for (_, s0, n0), (e, s, n) in zip(bow, waist):
        assert n == n0
        np.testing.assert_allclose(s, s0, rtol=0.1)
        assert np.all(np.abs(e) < 3.0 * s)
    rms0 = np.sqrt(np.mean([e ** 2 for e, _, _ in bow], axis=0))
    rms = np.sqrt(np.mean([e ** 2 for e, _, _ in waist], axis=0))
    assert np.all(rms <= 1.5 * rms0 + 0.03 * ARCMIN)


def test_a_filter_that_ignores_the_heading_reports_it_as_misalignment(bow):
    """Told 0 deg while the aircraft sits at -9 deg, the filter starts 9 deg off in yaw and
    reports the heading itself as misalignment (540' of yaw)."""
    e, _, _ = _errors(**{'aircraft.heading_on_deck_deg': -9.0, 'filter.heading_on_deck_deg': 0.0})[0]
    assert abs(e[2] / ARCMIN - 540.0) < 30.0


def test_ldv_beam_along_the_ships_axis_loses_a_turned_aircraft(bow):
    """A beam along the ship's x axis (2 m half width) loses an aircraft running at 9 deg to it
    after 2 m / sin 9 deg = 12.8 m of its 88.3 m stroke (2 g, 3 s): the last part of the stroke
    gets no match. Along the track it sees the whole stroke."""
    _, _, n_track = _errors(**{'aircraft.heading_on_deck_deg': -9.0})[0]
    _, _, n_ship = _errors(**{'aircraft.heading_on_deck_deg': -9.0, 'ldv.track_heading_deg': 0.0})[0]
    assert n_track == bow[0][2]
    # 12.8 m at 2 g is reached after sqrt(2 * 12.8 / 19.6) = 1.14 s of the 3 s stroke
    assert abs((n_track - n_ship) - 100 * (3.0 - 1.14)) < 10
