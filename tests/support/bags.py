"""Bag helpers of the tests: a copy of a bag without some topics (a run as a real log would be:
no truth), written with the project's bag writer."""
from __future__ import annotations

from pathlib import Path

from alignment_ros.bag import BagReader, BagWriter


def copy_without(bag: Path, out: Path, drop_prefix: str = '/truth/') -> dict[str, int]:
    """Write `out` holding every message of `bag` except those of topics starting with
    drop_prefix; return the copy's per-topic counts."""
    reader = BagReader(bag)
    kept = {t: ty for t, ty in reader.topics().items() if not t.startswith(drop_prefix)}
    counts = dict.fromkeys(kept, 0)
    with BagWriter(out) as w:
        for topic, type_name in kept.items():
            w.add_topic(topic, type_name)
        for m in reader.messages(sorted(kept)):
            w.write(m.topic, m.data, m.t_ns)
            counts[m.topic] += 1
    return counts
