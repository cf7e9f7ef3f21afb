"""Replay of a run whose filter matches the Doppler radar (seed001_13): replay.sh plays
/doppler/twist too, so the replayed filter reproduces the run's estimates exactly."""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_ros.bag import BagReader
from alignment_ros.replay import replay_topics

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=8.0', 'aircraft.catapult.launch_time_s=4.0', 'seed=7', 'filter.model=seed001_13',
        'doppler.enabled=true']


@pytest.fixture(scope='module')
def runs(tmp_path_factory) -> tuple[Path, Path]:
    base = tmp_path_factory.mktemp('doppler')
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'catapult_paper', '--out', str(base / 'run'),
           '--real-time-factor', '0']
    for s in SETS:
        cmd += ['--set', s]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    r = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(base / 'run'), '--out', str(base / 'replay')],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return base / 'run', base / 'replay'


def _estimates(bag: Path):
    from alignment_ros.summary import estimates_from_bag
    e = estimates_from_bag(bag)
    return e['t_ns'], e['misalignment'], e['sigma']


def test_replay_plays_the_doppler_stream_only_when_recorded():
    have = {'/clock': '', '/master/odom': '', '/aircraft/imu': '', '/doppler/twist': ''}
    play, wait = replay_topics(have, {'filter.model': 'seed001_13'})
    assert '/doppler/twist' in play and '/doppler/twist=1' in wait
    play, wait = replay_topics({'/doppler/twist': ''}, {'filter.model': 'vm15'})
    assert '/doppler/twist' in play and '/doppler/twist=1' not in wait
    play, _ = replay_topics({'/clock': ''}, {'filter.model': 'vm15'})
    assert '/doppler/twist' not in play


def test_seed001_replay_reproduces_the_run(runs):
    run, replay = runs
    assert '/doppler/twist' in BagReader(run / 'bag').topics()
    t_g, mu_g, sig_g = _estimates(run / 'bag')
    t_r, mu_r, sig_r = _estimates(replay / 'bag')
    assert np.array_equal(t_g, t_r) and np.array_equal(mu_g, mu_r) and np.array_equal(sig_g, sig_r)
    # and both are the batch pipeline's (the Doppler updates included)
    sc = scenario.load(str(run / 'scenario.yaml'))
    batch = pipeline.run(sc, keep_truth=False)
    assert batch.filter.counters.doppler_updates > 50
    assert np.max(np.abs(np.array([e.misalignment for e in batch.estimates]) - mu_g)) < 1e-9
