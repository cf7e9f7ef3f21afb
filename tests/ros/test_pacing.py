"""The ship's lead over the streams downstream (alignment_ros.pacing): a sample waits while a
watched stream is more than the lead behind it, a silent stream counts from t0."""
from __future__ import annotations

import pytest

from alignment_ros.pacing import LeadLimit

S = 1_000_000_000


def test_a_stream_behind_by_more_than_the_lead_holds_the_sample_back():
    lim = LeadLimit(['/a', '/b'], 2 * S, t0_ns=10 * S)
    assert lim.behind(12 * S) == []                  # nothing sent yet: counted at t0, 2 s = the lead
    assert lim.behind(12 * S + 1) == ['/a', '/b']
    lim.note('/a', 11 * S)
    assert lim.behind(13 * S) == ['/b']
    lim.note('/b', 11 * S + 1)
    assert lim.behind(13 * S) == []
    lim.note('/b', 5 * S)                            # an older stamp never moves it back
    assert lim.behind(13 * S) == []


def test_a_lead_of_zero_or_less_is_refused():
    with pytest.raises(ValueError):
        LeadLimit(['/a'], 0, 0)


class WallClock:
    """A settable wall clock (s)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_a_stream_silent_for_the_release_time_is_no_longer_waited_for_until_it_advances():
    wall = WallClock()
    lim = LeadLimit(['/a', '/b'], 2 * S, t0_ns=0, release_s=10.0, clock=wall)
    lim.note('/a', 5 * S)
    lim.note('/b', 5 * S)
    since = wall.now
    assert lim.holding(8 * S, since) == ['/a', '/b']     # both 3 s behind, the lead is 2 s
    wall.now += 6.0
    lim.note('/a', 7 * S)                                 # /a advances within the lead, /b is silent
    assert lim.holding(8 * S, since) == ['/b']
    wall.now += 4.0 + 1e-6                                # /b silent for 10 s of this wait: released
    assert lim.holding(8 * S, since) == []
    assert lim.releases == 1 and lim.released == {'/b'}
    assert lim.holding(20 * S, wall.now) == ['/a']       # a later sample no longer waits for /b
    lim.note('/b', 6 * S)                                 # it advances: waited for again
    assert lim.holding(20 * S, wall.now) == ['/a', '/b']
    assert lim.releases == 1


def test_the_release_time_counts_from_the_start_of_the_wait():
    """A stream that was silent long before the ship had to wait for it is not released at once."""
    wall = WallClock()
    lim = LeadLimit(['/a'], 2 * S, t0_ns=0, release_s=10.0, clock=wall)
    lim.note('/a', 1 * S)
    wall.now += 100.0
    since = wall.now
    assert lim.holding(4 * S, since) == ['/a']
    wall.now += 9.0
    assert lim.holding(4 * S, since) == ['/a']
    wall.now += 2.0
    assert lim.holding(4 * S, since) == []


def test_a_release_time_of_zero_is_refused():
    with pytest.raises(ValueError):
        LeadLimit(['/a'], S, 0, release_s=0.0)
