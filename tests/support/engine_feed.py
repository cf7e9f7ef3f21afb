"""Feeding an alignment engine events in an order other than the graph's publishing order."""
from __future__ import annotations


def feed_in_order(sc, events):
    """A fresh alignment engine for scenario `sc`, fed (stream, sample) events in the given order
    (stream 'imu', 'ldv', 'master' or 'doppler'), processed after each event and at the end.
    pipeline.align feeds the graph's publishing order; this is for any other order."""
    from alignment_core import pipeline
    from alignment_core.estimation.engine import TransferAlignment
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
    push = {'imu': f.push_imu, 'ldv': f.push_ldv, 'master': f.push_master, 'doppler': f.push_doppler}
    for stream, item in events:
        push[stream](item)
        f.process()
    f.process(final=True)
    return f


def random_interleaving(inp, rng):
    """The inputs' IMU, LDV and master streams as (stream, sample) events, interleaved at random in
    bursts of 1-39 samples (each stream keeps its own order: lags and bursts, as on a network)."""
    streams = [[('imu', s) for s in inp.imu], [('ldv', s) for s in inp.ldv], [('master', s) for s in inp.master]]
    merged = []
    while any(streams):
        i = rng.choice([k for k in range(3) if streams[k]])
        n = int(rng.integers(1, 40))
        merged += streams[i][:n]
        del streams[i][:n]
    return merged
