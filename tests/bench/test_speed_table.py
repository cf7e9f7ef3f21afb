"""bench/speed_table.py: a goal is met only when every measurement of it meets it; the block is
replaced in place, and only there."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / 'bench'))
import speed_table  # noqa: E402


def graph(rtf: float, startup: float, lost: int = 0) -> dict:
    return {'whole_run_rtf': rtf, 'startup_s': startup, 'lost': lost, 'sim_time_s': 60.0,
            'cpu_s': {'filter': 3.0, 'ship': None}}


def run(**over) -> dict:
    r = {'stamp': {'commit': 'abc1234', 'date': '2026-12-03', 'cpus': 2, 'load_start': 0.5, 'load_end': 1.0,
                   'command': 'scripts/bench.sh speed --publish'},
         'engine': {'median_us': 25.0, 'p95_us': 40.0},
         'kf': {'ours_us': 5.0, 'filterpy_us': 15.0},
         'pyins': {'pyins_us': 20000.0},
         'mc': {'deck': {'1': {'runs_per_min': 60.0, 'cpu_s_per_run': 1.0},
                         '2': {'runs_per_min': 100.0, 'cpu_s_per_run': 1.2}}},
         'graphs': [graph(8.5, 1.6), graph(8.1, 2.9)],
         'memory': {'peak_1h_mib': 1600.0, 'base_mib': 190.0, 'per_hour_mib': 1410.0}}
    r.update(over)
    return r


def verdicts(r: dict) -> dict[str, str]:
    return {goal: met for goal, _, _, met in speed_table.rows(r)}


def test_goals_at_their_targets_are_met():
    v = verdicts(run())
    assert [k for k, m in v.items() if m != 'met'] == ['Batch pipeline, peak RSS of a 1 h `deck` run']


@pytest.mark.parametrize('over, goal', [
    ({'engine': {'median_us': 25.1, 'p95_us': 40.0}}, 'Engine'),
    ({'kf': {'ours_us': 6.0, 'filterpy_us': 17.9}}, 'Bare'),          # 2.98x
    ({'graphs': [graph(9.0, 1.6), graph(7.99, 1.6)]}, 'Graph, default'),
    ({'graphs': [graph(9.0, 1.6), graph(9.0, 3.0)]}, 'Graph: first'),
    ({'graphs': [graph(9.0, 1.6), graph(9.0, 1.6, lost=1)]}, 'Graph: messages'),
    ({'mc': {'deck': {'2': {'runs_per_min': 99.9, 'cpu_s_per_run': 1.2}}}}, 'Monte Carlo'),
])
def test_one_measurement_short_of_its_target_is_not_met(over, goal):
    v = verdicts(run(**over))
    assert [k for k, m in v.items() if m == 'not met'] == [k for k in v if k.startswith(goal)]


def test_the_block_is_replaced_in_place_and_stamped(tmp_path):
    doc = tmp_path / 'a.md'
    doc.write_text('intro\n<!-- results:speed -->\nold\n<!-- /results:speed -->\nafter\n')
    other = tmp_path / 'b.md'
    other.write_text('no block here\n')
    written = speed_table.publish(run(), (doc, other))
    assert written == [doc]
    assert other.read_text() == 'no block here\n'
    text = doc.read_text()
    assert text.startswith('intro\n<!-- results:speed -->\n| goal |')
    assert text.endswith('<!-- /results:speed -->\nafter\n')
    assert 'old' not in text
    assert 'at commit `abc1234`, 2026-12-03, 2 CPUs, load average 0.5 at the start and 1.0 at the end' in text
    assert 'filter 3.0, 3.0' in text and 'ship' not in text.split('CPU seconds')[1].split('\n')[0]


def test_the_graph_estimate_row_needs_every_run_equal_to_the_batch():
    runs = [graph(9.0, 1.6), graph(9.0, 1.6)]
    runs[0]['same_estimate'], runs[1]['same_estimate'] = True, False
    v = verdicts(run(graphs=runs))
    assert v["Graph: the scored estimate, against the batch pipeline's on the same scenario"] == 'not met'
    runs[1]['same_estimate'] = True
    assert verdicts(run(graphs=runs))["Graph: the scored estimate, against the batch pipeline's on the same scenario"] \
        == 'met'
