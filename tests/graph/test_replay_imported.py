"""An imported log through the real replay path (scripts/import_log.sh, scripts/replay.sh: the
filter node in its own process): a short simulated catapult run written in the aerospace layout
(NED/FRD Euler degrees, rates, g, times from 0; the canonical one is replayed in-process by
tests/ros/test_importer.py), without truth. The replay's estimates equal the batch run's to
1e-6 rad, the origin and the IMU rate come from the bag, and the summary gives the estimate and
its 1-sigma without truth, and says so."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import yaml
from support.recorded_layouts import AEROSPACE_MAP, write_aerospace

from alignment_core import pipeline
from alignment_core.config import scenario as core_scenario
from alignment_ros.graph import params_yaml
from alignment_ros.summary import estimates_from_bag

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=14.0', 'aircraft.catapult.launch_time_s=8.0']


def test_truth_free_replay_of_an_imported_log(tmp_path):
    given = core_scenario.given_data('catapult_paper', core_scenario.parse_overrides(SETS))
    sc = core_scenario.resolve(given)
    inp = pipeline.simulate(sc)
    batch = pipeline.align(sc, inp)
    write_aerospace(tmp_path, sc, inp)
    (tmp_path / 'map.yaml').write_text(yaml.safe_dump(AEROSPACE_MAP))
    p = subprocess.run([str(ROOT / 'scripts/import_log.sh'), '--imu', str(tmp_path / 'imu.csv'),
                        '--master', str(tmp_path / 'master.csv'), '--ldv', str(tmp_path / 'ldv.csv'),
                        '--map', str(tmp_path / 'map.yaml'), '--out', str(tmp_path / 'bag')],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and 'warning' not in p.stderr, p.stdout + p.stderr
    # the scenario's filter section (its tuning, lever arm, heading on deck), as a user would give it;
    # the origin and the IMU rate come from the bag
    filt = {k: v for k, v in given.items() if k in ('filter', 'aircraft')}
    (tmp_path / 'params.yaml').write_text(params_yaml(filt, sc))
    r = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(tmp_path / 'bag'), '--out', str(tmp_path / 'replay'),
                        '--params-file', str(tmp_path / 'params.yaml')], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "origin 40.000000000, 116.000000000 deg: the importer's (bag metadata)" in r.stderr
    assert "IMU rate 100 Hz: the importer's (bag metadata)" in r.stderr
    assert 'no truth in the input: estimate and 1 sigma only' in r.stdout
    s = json.loads((tmp_path / 'replay' / 'summary.json').read_text())
    assert s['truth'] is False and s['complete'] is True and s['misalignment_truth_rad'] is None
    est = estimates_from_bag(tmp_path / 'replay' / 'bag')
    want = np.array([e.misalignment for e in batch.outputs])
    assert list(est['t_ns']) == [e.t_ns for e in batch.outputs]
    assert np.max(np.abs(est['misalignment'] - want)) < 1e-6
    assert s['misalignment_estimate_rad'] == est['misalignment'][-1].tolist()
    assert np.allclose(s['misalignment_sigma_rad'], batch.outputs[-1].misalignment_sigma, rtol=1e-6)
    # issue 18: the replay of an imported log leaves its pictures and report (no truth to draw),
    # and plot_bag.sh draws the imported bag itself (sensor streams only: the LDV's deck velocity)
    pngs = {f.name for f in (tmp_path / 'replay' / 'plots').glob('*.png') if f.stat().st_size > 0}
    assert {'misalignment.png', 'states.png', 'consistency.png'} <= pngs
    report = (tmp_path / 'replay' / 'report.md').read_text()
    assert 'plots/misalignment.png' in report
    q = subprocess.run([str(ROOT / 'scripts/plot_bag.sh'), str(tmp_path / 'bag'), '--out', str(tmp_path / 'p')],
                       capture_output=True, text=True, timeout=300)
    assert q.returncode == 0, q.stdout + q.stderr
    drawn = {f.name for f in (tmp_path / 'p').glob('**/*.png') if f.stat().st_size > 0}
    assert 'motion.png' in drawn and 'misalignment.png' not in drawn
    assert (tmp_path / 'p' / 'report.md').exists()
