"""Memory of slave_ins_node / ldv_node message handling without DDS traffic: the node's own
callbacks (pairing, core stage, conversions, send) driven with deck-scenario messages for a long
simulated time, publishers replaced by no-ops; RSS every 5000 samples and, with --trace, the
top tracemalloc growth sites between N and 2N samples.

    scripts/bench.sh node_memory slave [--samples 30000] [--trace]

A per-message retention shows as RSS (or traced bytes) growing linearly with the samples; the
soak's graph numbers (soak_memory.py) add what the DDS transport holds."""
from __future__ import annotations

import argparse
import gc
import tempfile
import tracemalloc
from pathlib import Path

import numpy as np
import rclpy

from alignment_core import pipeline
from alignment_core.config import scenario as core_scenario
from alignment_ros import convert, domain, graph


class NullPublisher:
    def publish(self, msg) -> None:
        pass


def rss_mib() -> float:
    for line in Path('/proc/self/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0
    return float('nan')


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('node', choices=('slave', 'ldv'))
    ap.add_argument('--samples', type=int, default=30000, help='samples per leg (two legs)')
    ap.add_argument('--trace', action='store_true', help='tracemalloc sites (slow)')
    a = ap.parse_args()
    given = core_scenario.given_data('deck', core_scenario.parse_overrides(['duration_s=7200']), None)
    sc = core_scenario.resolve(given)
    params = Path(tempfile.mkdtemp(prefix='node-memory-')) / 'params.yaml'
    graph.write_params(given, sc, params)
    rclpy.init(domain_id=domain.claim(), args=['node_memory', '--ros-args', '--params-file', str(params)])
    if a.node == 'slave':
        from slave_ins_node.node import SlaveInsNode as Node
    else:
        from ldv_node.node import LdvNode as Node
    node = Node()
    for topic in node._pubs:
        node._pubs[topic] = NullPublisher()
    ship = pipeline.ship_source(sc)
    aircraft = pipeline.SlaveImuStage(sc)
    chunk, k0 = 1000, 0

    def feed(n: int) -> None:
        nonlocal k0
        for _ in range(0, n, chunk):
            for s in ship.samples(((np.arange(chunk) + k0) * sc.dt_ns) / 1e9, sc.t0_ns, sc.dt_ns, k0):
                odom, accel = convert.ship_to_msgs(s)
                if a.node == 'slave':
                    node.on_odom(odom)
                    node.on_accel(accel)
                else:
                    node.on_ship(odom)
                    node.on_aircraft(convert.truth_to_msgs(aircraft.step(s)[0])[0])
            k0 += chunk
            if k0 % 5000 == 0:
                print(f'{k0} samples ({k0 * sc.dt_ns / 1e9:.0f} s): RSS {rss_mib():.1f} MiB, pending '
                      f'{len(node.pairs.a)}/{len(node.pairs.b)}', flush=True)

    feed(2000)
    if a.trace:
        tracemalloc.start(5)
    snaps, rss = [], []
    for leg in range(3):
        if leg:
            feed(a.samples)
        gc.collect()
        rss.append(rss_mib())
        snaps.append(tracemalloc.take_snapshot() if a.trace else None)
    per_h = (rss[2] - rss[1]) / a.samples * 3600.0 * sc.rate_hz
    print(f'{a.node}: RSS {rss[0]:.1f} -> {rss[1]:.1f} -> {rss[2]:.1f} MiB over 2 x {a.samples} samples '
          f'(second leg: {per_h:.2f} MiB per simulated hour)')
    if a.trace:
        total = [sum(st.size for st in s.statistics('filename')) for s in snaps]
        print(f'traced bytes per sample: leg 1 {(total[1] - total[0]) / a.samples:.2f}, '
              f'leg 2 {(total[2] - total[1]) / a.samples:.2f}')
        for st in snaps[2].compare_to(snaps[1], 'lineno')[:10]:
            print('  ', st)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
