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
