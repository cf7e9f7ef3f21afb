"""The air-data experiments in their quick versions: results files that do not depend on the
worker count, a report that renders, numbers that make physical sense, and the published
numbers still those this code gives."""
from __future__ import annotations

import csv

import numpy as np
import pytest

from alignment_experiments import publish
from alignment_experiments.air_data_catalogue import AIR_DATA_EXPERIMENTS
from alignment_experiments.cli import main


@pytest.mark.parametrize('name', sorted(AIR_DATA_EXPERIMENTS))
def test_quick_air_data_experiment(tmp_path, name):
    exp = AIR_DATA_EXPERIMENTS[name].quick()
    out = tmp_path / name
    assert main([name, '--quick', '--workers', '2', '--out', str(out)]) == 0
    rows = list(csv.DictReader((out / 'runs.csv').open()))
    assert len(rows) == len(exp.cells) * exp.seeds
    for r in rows:
        for q in ('mach', 'alpha_rad', 'beta_rad'):
            assert np.isfinite(float(r[f'{q}_max'])) and float(r[f'{q}_std']) > 0.0
        assert int(r['updates']) > 0
    md = (out / 'report.md').read_text()
    assert md.startswith('# ') and '## Results per cell' in md
    assert md.count('\n| ') >= len(exp.cells) + 1
    publish.check_fresh(name, out / 'runs.csv')


def test_worker_count_does_not_change_the_numbers(tmp_path):
    name = 'seed004_tables'
    base = ['--quick', '--seeds', '1']
    assert main([name, *base, '--workers', '1', '--out', str(tmp_path / 'one')]) == 0
    assert main([name, *base, '--workers', '2', '--out', str(tmp_path / 'two')]) == 0
    assert (tmp_path / 'one' / 'runs.csv').read_bytes() == (tmp_path / 'two' / 'runs.csv').read_bytes()
