"""`export ROS_DOMAIN_ID=N; scripts/run_graph.sh` runs the graph on domain N: it says so on
its first line, and a subscriber started from outside on N (scripts/echo.sh, which reads the
domain from the environment as rclpy does) hears the filter's output while the run goes on.

The domain is one no run of this project holds when the test starts (claimed and released);
the run locks it again itself."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

import yaml

from alignment_ros import domain

ROOT = Path(__file__).resolve().parents[2]
# short: 6 s of matching on deck, no catapult (nothing here depends on the launch)
SETS = ['duration_s=6.0', 'aircraft.catapult.enabled=false', 'seed=7']


def test_run_graph_honours_an_exported_domain(tmp_path):
    dom = domain.claim()
    domain.release(dom)
    env = dict(os.environ, ROS_DOMAIN_ID=str(dom))
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'catapult_paper', '--out', str(tmp_path / 'run'),
           '--real-time-factor', '2']
    for s in SETS:
        cmd += ['--set', s]
    run = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = run.stdout.readline()
        while first.startswith('setup.sh:'):         # a rebuild of the workspace first
            first = run.stdout.readline()
        assert first.split()[:1] == [f'ROS_DOMAIN_ID={dom}'], first + run.stderr.read()
        echo = subprocess.run([str(ROOT / 'scripts/echo.sh'), '/alignment/misalignment', '--once',
                               '--timeout', '60'], env=env, capture_output=True, text=True, timeout=120)
        out, err = run.communicate(timeout=300)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 0, out + err
    assert echo.returncode == 0, echo.stderr
    msg = yaml.safe_load(echo.stdout.partition('\n---\n')[0])
    assert msg['header']['frame_id'] == 'aircraft'
    assert set(msg['vector']) == {'x', 'y', 'z'}
