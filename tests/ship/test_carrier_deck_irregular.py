"""The realistic carrier deck's ship (`deck`: spectral sea state 5 from the port quarter,
20 kn, MMG course keeping) rolls irregularly at the carrier's roll period, unlike the papers'
one sinusoid per axis.

Expected values, independent of the code: a sinusoid's peak over its RMS is sqrt(2) = 1.41 at any
length; a narrow-band Gaussian process observed over N cycles reaches about sqrt(2 ln N) of its
RMS (Rayleigh-distributed peaks), 2.3 for 15 cycles of a 20 s roll in 300 s, so more than 1.6.
The carrier's roll natural period is 20 s (ship.roll_period_s) and a quartering sea at 20 kn
meets the ship at about that period, so the mean up-crossing period lies within 14-26 s."""
import numpy as np
import pytest

from alignment_core.config import scenario
from alignment_core.ship.motion import make_motion

DURATION_S = 300.0


@pytest.mark.parametrize('seed', [1, 2])
def test_deck_rolls_irregularly_at_its_roll_period(seed):
    sc = scenario.load('deck', seed=seed)
    assert sc.ship.mode == 'spectral' and sc.ship.course_keeping == 'mmg'
    t = np.arange(0.0, DURATION_S, 0.01)
    roll = make_motion(sc.ship, sc.seed).batch(t)['euler'][:, 0]
    roll = roll - roll.mean()
    rms = np.sqrt(np.mean(roll**2))
    assert np.max(np.abs(roll)) / rms > 1.6
    up = np.count_nonzero((roll[:-1] < 0.0) & (roll[1:] >= 0.0))
    assert 14.0 <= DURATION_S / up <= 26.0


def test_paper_deck_rolls_as_one_sinusoid():
    """The contrast: deck_paper's roll peak over RMS is a sinusoid's sqrt(2) (within the 300 s
    window's partial cycle), below the irregular sea's 1.6."""
    sc = scenario.load('deck_paper')
    roll = make_motion(sc.ship, sc.seed).euler(np.arange(0.0, DURATION_S, 0.01))[0][:, 0]
    roll = roll - roll.mean()
    assert np.max(np.abs(roll)) / np.sqrt(np.mean(roll**2)) == pytest.approx(np.sqrt(2.0), abs=0.05)
