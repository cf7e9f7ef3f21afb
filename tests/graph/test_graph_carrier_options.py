"""Graph integration of the carrier options (issue 16): a beam LDV (its rank-1 /ldv/twist read back
by the filter node, the ldv_node computing the reflector's motion from the aircraft truth's body
rate), a Schuler ship INS at 50 Hz, and a lever arm surveyed 5 cm off with lever-arm states (the
filter node draws the same survey error from its own parameters): the graph gives the batch's
estimates. The beam's direction is rebuilt from the covariance (an eigenvector: the last bits
and its sign may differ, the projection does not), hence a tolerance, not bit equality.

Not here: a master latency (its run-out past the end: tests/graph/test_graph_run_out.py). The
master node's jittered stamps are checked against the stage in tests/sensors/test_sensor_nodes.py."""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=4.0', 'seed=5', 'ldv.mode=beam', 'ldv.reflector_m=[2.0,0.3,-0.8]', 'master.model=schuler',
        'master.rate_hz=50.0', 'aircraft.lever_arm_survey_sigma_m=0.05', 'filter.lever_arm_states=true']


def test_carrier_options_graph_equals_batch(tmp_path):
    out = tmp_path / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'deck_paper', '--out', str(out), '--real-time-factor', '0',
           '--timeout', '900']
    for s in SETS:
        cmd += ['--set', s]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=1000)
    assert p.returncode == 0, p.stdout + p.stderr
    assert 'lost messages: 0' in p.stdout
    sc = scenario.load(str(out / 'scenario.yaml'))
    assert sc.filter.ldv_mode == 'beam' and sc.filter.lever_arm_m != sc.aircraft.lever_arm_m
    batch = pipeline.run(sc, keep_truth=False)
    assert batch.filter.counters.updates > 150
    from alignment_ros.summary import estimates_from_bag
    e = estimates_from_bag(out / 'bag')
    t_b = np.array([x.t_ns for x in batch.estimates])
    mu_b = np.array([x.misalignment for x in batch.estimates])
    sig_b = np.array([x.misalignment_sigma for x in batch.estimates])
    assert np.array_equal(e['t_ns'], t_b)
    assert np.max(np.abs(e['misalignment'] - mu_b)) < 1e-9
    np.testing.assert_allclose(e['sigma'], sig_b, rtol=1e-9)
