"""The ship's lead over the streams downstream of it: the ship node publishes a sample only when
every watched stream has reached within `max_lead_ns` of its stamp. A node that pairs two
streams (the LDV: the ship's odometry with the slave's aircraft truth) otherwise buffers the
faster one for as long as the slower lags, which at an unpaced real-time factor grows with the
run; with the lead bounded, every such buffer holds at most the lead's samples. Stamps are
untouched: the numbers are the same at any lead."""
from __future__ import annotations

from collections.abc import Iterable


class LeadLimit:
    """Latest stamp (ns) seen on each watched stream, against the sample about to be sent."""

    def __init__(self, topics: Iterable[str], max_lead_ns: int, t0_ns: int) -> None:
        if max_lead_ns <= 0:
            raise ValueError(f'max_lead_ns must be > 0, got {max_lead_ns}')
        self.max_lead_ns = max_lead_ns
        self.t0_ns = t0_ns
        self.latest: dict[str, int | None] = dict.fromkeys(topics)

    def note(self, topic: str, t_ns: int) -> None:
        last = self.latest.get(topic)
        if last is None or t_ns > last:
            self.latest[topic] = t_ns

    def behind(self, t_ns: int) -> list[str]:
        """The watched streams more than the lead behind t_ns (one that has sent nothing yet
        counts as at t0)."""
        floor = t_ns - self.max_lead_ns
        return [t for t, last in self.latest.items() if (self.t0_ns if last is None else last) < floor]
