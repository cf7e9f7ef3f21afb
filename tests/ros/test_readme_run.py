"""scripts/readme_run.sh's rendering: the README block between its markers is replaced by the
run's result table (summary.json's numbers in arcmin), its plot and the command; the rest of the
README is untouched; a run that is incomplete or not the catapult changes nothing. And the
committed README carries such a block whose image exists."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from alignment_ros import readme_run

ROOT = Path(__file__).resolve().parents[2]
ARCMIN = math.pi / 180 / 60
README = 'intro\n<!-- run:example -->\nold\n<!-- /run:example -->\ntail\n'


def _run(tmp_path: Path, complete: bool = True, scenario: str = 'catapult') -> Path:
    run = tmp_path / 'run'
    (run / 'plots').mkdir(parents=True)
    (run / 'plots' / 'misalignment.png').write_bytes(b'\x89PNG\r\n\x1a\nfake')
    s = {'complete': complete, 'scenario': scenario, 'sim_time_s': 68.0, 'scored_at_s': 64.0,
         'misalignment_truth_rad': [15 * ARCMIN, -10 * ARCMIN, -30 * ARCMIN],
         'misalignment_estimate_rad': [15.047 * ARCMIN, -10.034 * ARCMIN, -29.963 * ARCMIN],
         'misalignment_sigma_rad': [0.068 * ARCMIN, 0.069 * ARCMIN, 0.084 * ARCMIN]}
    (run / 'summary.json').write_text(json.dumps(s))
    return run


@pytest.fixture
def top(tmp_path, monkeypatch) -> Path:
    top = tmp_path / 'top'
    top.mkdir()
    (top / 'README.md').write_text(README)
    monkeypatch.setattr(readme_run, 'root', lambda: top)
    return top


def test_the_block_is_rendered_from_the_run(top, tmp_path):
    assert readme_run.main(['--from', str(_run(tmp_path))]) == 0
    text = (top / 'README.md').read_text()
    assert text.startswith('intro\n<!-- run:example -->\n') and text.endswith('<!-- /run:example -->\ntail\n')
    assert 'old' not in text
    assert '| y (pitch) | -10.000 | -10.034 | -0.034 | 0.069 |' in text
    assert f'![The misalignment estimate of this run]({readme_run.IMAGE.as_posix()})' in text
    assert '`scripts/run_graph.sh --scenario catapult`' in text
    assert (top / readme_run.IMAGE).read_bytes().endswith(b'fake')


@pytest.mark.parametrize('complete, scenario', [(False, 'catapult'), (True, 'deck')])
def test_a_wrong_run_changes_nothing(top, tmp_path, complete, scenario):
    assert readme_run.main(['--from', str(_run(tmp_path, complete, scenario))]) == 1
    assert (top / 'README.md').read_text() == README


def test_the_committed_readme_has_the_block_and_its_image():
    text = (ROOT / 'README.md').read_text()
    block = readme_run.BLOCK_RE.search(text)
    assert block is not None and '| x (roll) |' in block.group(2)
    assert (ROOT / readme_run.IMAGE).read_bytes().startswith(b'\x89PNG')
