"""Memory of a node's message handling without DDS traffic: the node's own subscription callbacks
(pairing, core stage or filter engine, conversions, send) driven with deck-scenario messages for a
long simulated time, publishers replaced by no-ops; RSS every 5000 samples and, with --trace, the
top tracemalloc growth sites between N and 2N samples.

    scripts/bench.sh node_memory {slave,ldv,master,filter} [--samples 30000] [--trace]

slave, ldv and master are fed the ship model's samples (convert.ship_to_msgs) chunk by chunk; the
filter the deck scenario's IMU, LDV and master streams of pipeline.simulate as convert's
messages, in the order pipeline.align pushes them. A per-message retention shows as RSS (or traced
bytes) growing linearly with the samples; the soak's graph numbers (soak_memory.py) add what the
DDS transport holds."""
from __future__ import annotations

import argparse
import gc
import tempfile
import tracemalloc
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import rclpy

from alignment_core import pipeline
from alignment_core.config import scenario as core_scenario
from alignment_ros import convert, domain, graph

CHUNK = 1000
WARMUP = 2000


class NullPublisher:
    def publish(self, msg) -> None:
        pass


def rss_mib() -> float:
    for line in Path('/proc/self/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0
    return float('nan')


def node_class(name: str):
    if name == 'slave':
        from slave_ins_node.node import SlaveInsNode
        return SlaveInsNode
    if name == 'ldv':
        from ldv_node.node import LdvNode
        return LdvNode
    if name == 'master':
        from master_ins_node.node import MasterInsNode
        return MasterInsNode
    from alignment_filter_node.node import AlignmentFilterNode
    return AlignmentFilterNode


def ship_steps(name: str, node, sc) -> Iterator[None]:
    """One step per ship sample: the slave, LDV or master node's callbacks for it."""
    ship = pipeline.ship_source(sc)
    aircraft = pipeline.SlaveImuStage(sc)
    k0 = 0
    while True:
        for s in ship.samples(((np.arange(CHUNK) + k0) * sc.dt_ns) / 1e9, sc.t0_ns, sc.dt_ns, k0):
            odom, accel = convert.ship_to_msgs(s)
            if name == 'slave':
                node.on_odom(odom)
                node.on_accel(accel)
            elif name == 'ldv':
                node.on_ship(odom)
                node.on_aircraft(convert.truth_to_msgs(aircraft.step(s)[0])[0])
            else:
                node.on_ship(odom)
            yield
        k0 += CHUNK


def filter_steps(node, sc) -> Iterator[None]:
    """One step per ship sample k: the IMU sample k-1, then the LDV and master samples stamped up
    to k's stamp (pipeline.align's order), each as the message its node publishes."""
    inp = pipeline.simulate(sc)
    gyro_var, accel_var = sc.imu.arw ** 2 * sc.rate_hz, sc.imu.vrw ** 2 * sc.rate_hz
    j_ldv = j_master = 0
    for k in range(len(inp.ships)):
        t = int(inp.ships.t_ns[k])
        if k > 0:
            node.on_imu(convert.imu_to_msg(inp.imu[k - 1], gyro_var, accel_var))
        while j_ldv < len(inp.ldv) and inp.ldv[j_ldv].t_ns <= t:
            node.on_ldv(convert.ldv_to_msg(inp.ldv[j_ldv]))
            j_ldv += 1
        while j_master < len(inp.master) and inp.master[j_master].t_ns <= t:
            node.on_master(convert.master_to_msg(inp.master[j_master]))
            j_master += 1
        yield


def pending(name: str, node) -> str:
    if name in ('slave', 'ldv'):
        return f'pending {len(node.pairs.a)}/{len(node.pairs.b)}'
    if name == 'filter':
        return f'pending {node.engine.diagnostics().pending}, outputs {node.n_out}'
    return f'outputs {node.n_out}'


def measure(name: str, samples: int, trace: bool, feed: Callable[[int], None], rate_hz: float) -> None:
    """RSS (and traced bytes) after the warm-up, after N and after 2N more samples."""
    feed(WARMUP)
    if trace:
        tracemalloc.start(5)
    snaps, rss = [], []
    for leg in range(3):
        if leg:
            feed(samples)
        gc.collect()
        rss.append(rss_mib())
        snaps.append(tracemalloc.take_snapshot() if trace else None)
    per_h = (rss[2] - rss[1]) / samples * 3600.0 * rate_hz
    print(f'{name}: RSS {rss[0]:.1f} -> {rss[1]:.1f} -> {rss[2]:.1f} MiB over 2 x {samples} samples '
          f'(second leg: {per_h:.2f} MiB per simulated hour, '
          f'{(rss[2] - rss[1]) * 2 ** 20 / samples * 1e5 / 2 ** 20:.2f} MiB per 100k samples)')
    if trace:
        total = [sum(st.size for st in s.statistics('filename')) for s in snaps]
        print(f'traced bytes per sample: leg 1 {(total[1] - total[0]) / samples:.2f}, '
              f'leg 2 {(total[2] - total[1]) / samples:.2f}')
        for st in snaps[2].compare_to(snaps[1], 'lineno')[:10]:
            print('  ', st)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('node', choices=('slave', 'ldv', 'master', 'filter'))
    ap.add_argument('--samples', type=int, default=30000, help='samples per leg (two legs)')
    ap.add_argument('--trace', action='store_true', help='tracemalloc sites (slow)')
    a = ap.parse_args()
    given = core_scenario.given_data('deck_paper', core_scenario.parse_overrides(['duration_s=7200']), None)
    sc = core_scenario.resolve(given)
    params = Path(tempfile.mkdtemp(prefix='node-memory-')) / 'params.yaml'
    graph.write_params(given, sc, params)
    rclpy.init(domain_id=domain.claim(), args=['node_memory', '--ros-args', '--params-file', str(params)])
    node = node_class(a.node)()
    for topic in node._pubs:
        node._pubs[topic] = NullPublisher()
    if a.node == 'filter':          # the batch streams of just the samples fed (plus a margin)
        duration_s = (WARMUP + 2 * a.samples + 10) / sc.rate_hz
        sim = core_scenario.resolve(core_scenario.given_data(
            'deck_paper', core_scenario.parse_overrides([f'duration_s={duration_s}']), None))
        steps = filter_steps(node, sim)
    else:
        steps = ship_steps(a.node, node, sc)
    done = 0

    def feed(n: int) -> None:
        nonlocal done
        for _ in range(n):
            next(steps)
            done += 1
            if done % 5000 == 0:
                print(f'{done} samples ({done / sc.rate_hz:.0f} s): RSS {rss_mib():.1f} MiB, '
                      f'{pending(a.node, node)}', flush=True)

    measure(a.node, a.samples, a.trace, feed, sc.rate_hz)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
