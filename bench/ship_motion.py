"""Wall time of the spectral ship truth, and (optionally) its INS consistency over the hour.

    python bench/ship_motion.py [--hours 1] [--rate 100] [--sea-state 6] [--frequencies 150]
                                [--directions 15] [--repeat 3] [--ins] [--mmg] [--node]

Synthesis: one hour of sea state 6 at 100 Hz with 150 x 15 = 2250 wave components, timed as
(a) the wave-frequency DOF alone (6 DOF x position, rate, acceleration), (b) the whole truth
as arrays (Euler, body rate and angular acceleration, ENU velocity and acceleration, geodetic
and world positions), (c) the list of ShipSample records the batch pipeline consumes
(`pipeline.ship_samples`). Best of --repeat runs. Target: (c) under 30 s on two cores.

--ins: the strapdown check of tests/ship/test_ship_ins.py over the whole duration (noise-free
slave IMU at a 100 m lever arm and at the master point, strapdown from the true initial
state); prints the largest attitude and velocity errors (targets 1e-6 rad, 1e-3 m/s).

--mmg: `course_keeping: mmg` instead of the straight course (carrier, a 90 deg turn ordered
at 60 s, 25 kn of wind); times (a') the MMG + autopilot integration over the hour (RK4,
0.5 s) and the low-frequency kinematics at every sample, (a) the wave-frequency DOF along the
track (direct evaluation on the 0.1 s knots, then the quintic interpolation), (b), (c).

--node: the ship_motion_node's publishing step without ROS (one `samples` call for one
sample and its conversion to Odometry + AccelStamped, as `ShipMotionNode.run` does), for
--node-samples consecutive samples: the sustained rate it can publish at (samples per wall
second) and the real-time factor that allows at --rate.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'tests' / 'ship'))


def best(fn, repeat: int) -> tuple[float, object]:
    out, wall = None, np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        wall = min(wall, time.perf_counter() - t)
    return wall, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--hours', type=float, default=1.0)
    ap.add_argument('--rate', type=float, default=100.0)
    ap.add_argument('--sea-state', type=int, default=6)
    ap.add_argument('--frequencies', type=int, default=150)
    ap.add_argument('--directions', type=int, default=15)
    ap.add_argument('--speed', type=float, default=20.0)
    ap.add_argument('--wave-heading', type=float, default=120.0)
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--ins', action='store_true')
    ap.add_argument('--mmg', action='store_true')
    ap.add_argument('--node', action='store_true')
    ap.add_argument('--node-samples', type=int, default=3000)
    a = ap.parse_args()
    ov = {'ship.mode': 'spectral', 'ship.sea_state': a.sea_state, 'ship.speed_kn': a.speed,
          'ship.wave_heading_deg': a.wave_heading, 'ship.n_frequencies': a.frequencies,
          'ship.n_directions': a.directions, 'duration_s': a.hours * 3600.0, 'rate_hz': a.rate}
    if a.mmg:
        ov.update({'ship.course_keeping': 'mmg', 'ship.turn_at_s': 60.0,
                   'ship.turn_to_deg': 120.0, 'ship.wind_speed_kn': 25.0, 'ship.wind_from_deg': 70.0})
    sc = scenario.load('deck_paper', ov)
    t_build, src = best(lambda: pipeline.ship_source(sc), a.repeat)
    tau = np.arange(sc.n_samples) * sc.dt_ns / 1e9
    print(f'sea state {a.sea_state}: Hs {src.sea.hs_m} m, Tp {src.sea.tp_s} s; {len(src.comps)} '
          f'components; {sc.n_samples} samples ({a.hours} h at {a.rate} Hz); '
          f'course keeping {sc.ship.course_keeping}; {os.cpu_count()} CPUs')
    print(f'  build (spectrum, RAOs)            {t_build:8.3f} s')
    if a.mmg:
        t_lf, _ = best(lambda: pipeline.ship_source(sc).track.kinematics(tau), a.repeat)
        print(f"  MMG track + LF kinematics (a')    {t_lf:8.3f} s")
        t_wf, _ = best(lambda: pipeline.ship_source(sc).wf.at(tau), a.repeat)
    else:
        t_wf, _ = best(lambda: src.wf.evaluate(tau), a.repeat)
    print(f'  wave-frequency DOF (N x 19)       {t_wf:8.3f} s')
    t_b, _ = best(lambda: src.batch(tau), a.repeat)
    print(f'  whole truth as arrays             {t_b:8.3f} s')
    t_s, _ = best(lambda: pipeline.ship_samples(sc), a.repeat)
    print(f'  pipeline.ship_samples (records)   {t_s:8.3f} s   -> {a.hours * 3600 / t_s:,.0f}x real time')
    if a.node:
        node_rate(sc, a.node_samples, a.rate)
    if a.ins:
        from test_ship_ins import NOISE_OFF, strapdown_errors
        for arm in ([90.0, -40.0, 15.0], [0.0, 0.0, 0.0]):
            sci = scenario.load('deck_paper', {**ov, **NOISE_OFF, 'aircraft.lever_arm_m': arm})
            t = time.perf_counter()
            att, vel, _ = strapdown_errors(sci)
            n = len(att)
            print(f'  INS consistency, lever arm {arm} m over {a.hours} h ({time.perf_counter() - t:.0f} s): '
                  f'attitude {att.max():.2e} rad, velocity {vel.max():.2e} m/s '
                  f'(at 10 min: {att[:min(n, 60000)].max():.2e} rad, {vel[:min(n, 60000)].max():.2e} m/s)')


def node_rate(sc, n: int, rate: float) -> None:
    """The node's per-sample work (ShipMotionNode.run without DDS): one-sample `samples` and
    the message conversion, from a fresh source (the MMG track and the wave blocks are built
    as the samples ask for them, as in the node)."""
    from alignment_ros import convert
    src = pipeline.ship_source(sc)
    n = min(n, sc.n_samples)
    t = time.perf_counter()
    for k in range(n):
        s = src.samples(np.array([(k * sc.dt_ns) / 1e9]), sc.t0_ns, sc.dt_ns, k0=k)[0]
        convert.ship_to_msgs(s)
    wall = time.perf_counter() - t
    print(f'  node publishing step: {n} samples in {wall:.2f} s -> {n / wall:,.0f} samples/s, '
          f'real-time factor {n / wall / rate:.1f} at {rate:g} Hz')


if __name__ == '__main__':
    main()
