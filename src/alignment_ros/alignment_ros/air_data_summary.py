"""The air-data part of a run's summary: the estimates of /air_data/state against
/truth/air_data/state at the same stamps (the arrays carry no stamp: each is paired with the
stamped message published with it, /air_data/velocity and /truth/wind), as RMS over the run
after its first 10 s of estimates and the error at the last estimate, each with its 1-sigma."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import topics
from .air_data_convert import msg_to_labelled
from .bag_topics import BagTopics, topics_of
from .convert import to_ns

SHOWN = (('mach', 1.0, ''), ('alpha_rad', 180.0 / np.pi, 'deg'), ('beta_rad', 180.0 / np.pi, 'deg'),
         ('tas_mps', 1.0, 'm/s'), ('wind_east_mps', 1.0, 'm/s'), ('wind_north_mps', 1.0, 'm/s'),
         ('wind_up_mps', 1.0, 'm/s'))
SETTLE_S = 10.0
TOPICS = (topics.AIR_DATA_STATE, topics.AIR_DATA_VELOCITY, topics.TRUTH_AIR_DATA_STATE, topics.TRUTH_WIND)
"""What the score reads (the estimates and their stamps, the truth and its stamps)."""


def _stamped_arrays(bag: Path | BagTopics, array_topic: str, stamp_topic: str
                    ) -> dict[int, tuple[tuple[str, ...], np.ndarray]]:
    have = topics_of(bag, (array_topic, stamp_topic))
    arrays, stamps = have.decoded(array_topic), have.decoded(stamp_topic)
    out = {}
    for a, s in zip(arrays, stamps):
        _, labels, data = msg_to_labelled(a)
        out[to_ns(s.header.stamp)] = (labels, data)
    return out


def score(bag: Path | BagTopics) -> dict | None:
    """{'estimates': N, 'rms': {label: ...}, 'last': {label: (error, sigma)}, 't_last_s'} or
    None when the bag holds no air-data estimate."""
    est = _stamped_arrays(bag, topics.AIR_DATA_STATE, topics.AIR_DATA_VELOCITY)
    if not est:
        return None
    truth = _stamped_arrays(bag, topics.TRUTH_AIR_DATA_STATE, topics.TRUTH_WIND)
    common = sorted(set(est) & set(truth))
    if not common:
        return {'estimates': len(est), 'paired': 0}
    t0 = common[0]
    err: dict[str, list[float]] = {n: [] for n, _, _ in SHOWN}
    last = {}
    for t in common:
        labels, data = est[t]
        tl, tv = truth[t]
        for n, _, _ in SHOWN:
            e = float(data[0, labels.index(n)] - tv[0, tl.index(n)])
            if t - t0 >= SETTLE_S * 1e9:
                err[n].append(e)
            last[n] = (e, float(data[1, labels.index(n)]))
    return {'estimates': len(est), 'paired': len(common), 't_first_s': t0 * 1e-9, 't_last_s': common[-1] * 1e-9,
            'rms': {n: float(np.sqrt(np.mean(np.square(v)))) if v else None for n, v in err.items()},
            'last': last}


def table_lines(s: dict) -> list[str]:
    if s.get('paired', 0) == 0:
        return [f"air data: {s.get('estimates', 0)} estimates, none paired with the truth"]
    lines = [f"air data: {s['paired']} estimates from t = {s['t_first_s']:.2f} s; RMS after its first "
             f"{SETTLE_S:.0f} s, and the error at t = {s['t_last_s']:.2f} s",
             f"{'':<16}{'RMS':>10}{'error':>10}{'1 sigma':>10}"]
    for n, scale, unit in SHOWN:
        rms = s['rms'][n]
        e, sig = s['last'][n]
        name = n.replace('_rad', '').replace('_mps', '') + (f' ({unit})' if unit else '')
        shown = '-' if rms is None else f'{rms * scale:.4g}'
        lines.append(f"{name:<16}{shown:>10}{e * scale:>10.4g}{sig * scale:>10.4g}")
    return lines
