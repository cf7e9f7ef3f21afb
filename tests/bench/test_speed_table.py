"""bench/speed_table.py: a goal is met only when every measurement of it meets it, shown values
never round onto a target they miss, unmeasured goals are listed, and only the speed block of a
file is replaced."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / 'bench'))
import speed_table  # noqa: E402

ESTIMATE_ROW = "Graph: the scored estimate, against the batch pipeline's on the same scenario"
MEMORY_ROW = 'Batch pipeline, peak RSS of a 1 h `deck` run'


def graph(rtf: float, startup: float, lost: int = 0, same: bool = True) -> dict:
    return {'whole_run_rtf': rtf, 'startup_s': startup, 'lost': lost, 'sim_time_s': 60.0, 'same_estimate': same,
            'cpu_s': {'filter': 3.0, 'ship': None}}


def mc(rpm: float) -> dict:
    return {'1': {'runs_per_min': rpm / 2, 'cpu_s_per_run': 1.0}, '2': {'runs_per_min': rpm, 'cpu_s_per_run': 1.2}}


def run(**over) -> dict:
    r = {'stamp': {'commit': 'abc1234', 'date': '2026-12-03', 'cpus': 2, 'load_start': 0.5, 'load_end': 1.0,
                   'command': 'scripts/bench.sh speed --publish', 'settings': {'runs': 4}},
         'engine': {'median_us': 25.0, 'p95_us': 40.0},
         'kf': {'ours_us': 5.0, 'filterpy_us': 15.0},
         'pyins': {'pyins_us': 20000.0},
         'mc': {'deck': mc(100.0), 'deck_paper': mc(150.0)},
         'graphs': [graph(8.5, 1.6), graph(8.1, 2.9)],
         'memory': {'peak_1h_mib': 1600.0, 'peak_300s_mib': 300.0, 'import_only_mib': 250.0,
                    'per_hour_mib': 1410.0}}
    r.update(over)
    return r


def verdicts(r: dict) -> dict[str, str]:
    return {goal: met for goal, _, _, met in speed_table.rows(r)}


def test_goals_at_their_targets_are_met():
    v = verdicts(run())
    assert len(v) == 9
    assert [k for k, m in v.items() if m != 'met'] == [MEMORY_ROW]
    assert v[MEMORY_ROW] == 'reported'


@pytest.mark.parametrize('over, goal', [
    ({'engine': {'median_us': 25.1, 'p95_us': 40.0}}, 'Engine'),
    ({'kf': {'ours_us': 6.0, 'filterpy_us': 17.9}}, 'Bare'),          # 2.98x
    ({'graphs': [graph(9.0, 1.6), graph(7.99, 1.6)]}, 'Graph, default'),
    ({'graphs': [graph(9.0, 1.6), graph(9.0, 3.0)]}, 'Graph: first'),
    ({'graphs': [graph(9.0, 1.6), graph(9.0, 1.6, lost=1)]}, 'Graph: messages'),
    ({'graphs': [graph(9.0, 1.6), graph(9.0, 1.6, same=False)]}, 'Graph: the scored'),
    ({'mc': {'deck': mc(99.9), 'deck_paper': mc(150.0)}}, 'Monte Carlo, 300 s `deck`'),
])
def test_one_measurement_short_of_its_target_is_not_met(over, goal):
    v = verdicts(run(**over))
    assert [k for k, m in v.items() if m == 'not met'] == [k for k in v if k.startswith(goal)]


@pytest.mark.parametrize('over, shown', [
    ({'kf': {'ours_us': 5.0, 'filterpy_us': 14.98}}, '2.99x'),          # 2.996x
    ({'graphs': [graph(7.996, 1.6)]}, '7.99 (1 runs)'),
    ({'engine': {'median_us': 25.1, 'p95_us': 40.0}}, '26 us median'),
    ({'mc': {'deck': mc(99.96), 'deck_paper': mc(150.0)}}, '99.9 runs/min'),
])
def test_a_value_that_misses_its_target_is_never_shown_as_meeting_it(over, shown):
    measured = {goal: m for goal, _, m, _ in speed_table.rows(run(**over))}
    assert any(shown in m for m in measured.values()), measured


def test_goals_the_run_did_not_measure_are_listed():
    r = run(graphs=[], mc={'deck': mc(120.0)})
    del r['engine'], r['memory']
    v = verdicts(r)
    assert len(v) == 9
    missing = [k for k, m in v.items() if m == speed_table.NOT_MEASURED]
    assert len(missing) == 7                    # deck_paper, the engine, the graph's four, memory
    assert v['Monte Carlo, 300 s `deck`'] == 'met'


def test_only_the_speed_block_is_replaced_and_stamped(tmp_path):
    other = '<!-- results:seed000_table1 -->\nkept\n<!-- /results:seed000_table1 -->\n'
    doc = tmp_path / 'page'
    doc.write_text('intro\n<!-- results:speed -->\nold\n<!-- /results:speed -->\n' + other + 'after\n')
    written = speed_table.publish(run(), (doc,))
    assert written == [doc]
    text = doc.read_text()
    assert text.startswith('intro\n<!-- results:speed -->\n| goal |')
    assert text.endswith('<!-- /results:speed -->\n' + other + 'after\n')
    assert 'old' not in text
    assert ('Measured by `scripts/bench.sh speed --publish` (runs 4) at commit `abc1234`, 2026-12-03, 2 CPUs, '
            'load average 0.5 at the start and 1.0 at the end') in text
    assert 'filter 3.0, 3.0' in text and 'ship' not in text.split('CPU seconds')[1].split('\n')[0]


def test_a_target_without_its_block_writes_nothing(tmp_path):
    good, bad = tmp_path / 'with_block', tmp_path / 'without_end'
    good.write_text('<!-- results:speed -->\nold\n<!-- /results:speed -->\n')
    bad.write_text('<!-- results:speed -->\nno end marker\n')
    with pytest.raises(ValueError, match='without_end'):
        speed_table.publish(run(), (good, bad))
    assert good.read_text() == '<!-- results:speed -->\nold\n<!-- /results:speed -->\n'


def test_the_stamp_names_the_processor_when_the_run_recorded_it(tmp_path):
    """A run before the stamp had a 'cpu' field renders as before (the test above)."""
    doc = tmp_path / 'page'
    doc.write_text('<!-- results:speed -->\n<!-- /results:speed -->\n')
    r = run()
    r['stamp']['cpu'] = 'AMD EPYC 2.6 GHz'
    speed_table.publish(r, (doc,))
    assert '2026-12-03, 2 CPUs (AMD EPYC 2.6 GHz), load average 0.5 at the start' in doc.read_text()


def test_the_transport_line_gives_its_share_of_each_run():
    dds = {'a_us': 30.0, 'b_us': 5.0, 'c_us': 20.0,
           'runs': [{'transport_cpu_s': 4.0, 'graph_cpu_s': 20.0, 'rtf_bound': 34.0},
                    {'transport_cpu_s': 5.0, 'graph_cpu_s': 25.0, 'rtf_bound': 27.2}]}
    text = speed_table.render(run(dds=dds))
    line = next(x for x in text.split('\n') if x.startswith('The DDS transport alone'))
    assert '30 us of CPU per message published plus 5 us per reader, and 20 us' in line
    assert "4.0, 5.0 CPU s against the processes' (after their start-up) 20.0, 25.0 (20 %, 20 %)" in line
    assert '34x, 27x real time' in line
    assert 'Reading an Odometry' not in line
    dds['read_us'] = {'nav_msgs/msg/Odometry': {'rclpy_us': 40.2, 'wire_us': 8.4}}
    line = next(x for x in speed_table.render(run(dds=dds)).split('\n') if x.startswith('The DDS transport alone'))
    assert line.endswith("Reading an Odometry from its bytes took 40 us through rclpy's conversion and 8 us "
                         "through the nodes' reader (alignment_ros/wire.py).")
    assert 'The DDS transport' not in speed_table.render(run())


def test_the_transport_line_says_when_its_benchmark_ran_a_setting_again():
    dds = {'a_us': 30.0, 'b_us': 5.0, 'c_us': 20.0, 'failures': [], 'stopped_after_report': 0,
           'runs': [{'transport_cpu_s': 4.0, 'graph_cpu_s': 20.0, 'rtf_bound': 34.0}]}

    def line() -> str:
        return next(x for x in speed_table.render(run(dds=dds)).split('\n') if x.startswith('The DDS transport'))
    assert 'ran again' not in line()
    dds['failures'], dds['stopped_after_report'] = ['2 readers: 1 of 2 subscribers reported nothing'], 1
    assert line().endswith('In that benchmark 1 setting(s) failed and ran again (2 readers: 1 of 2 subscribers '
                           'reported nothing), and 1 process(es) hung after reporting and were stopped.')


def test_the_monte_carlo_line_says_how_many_runs_it_timed():
    text = speed_table.render(run())
    assert '100.0 runs/min on 2 workers (4 runs, 1.2 CPU s per run)' in text


def test_each_worker_count_shows_its_own_runs():
    """Runs counted per worker setting (--runs-2): the two-worker line gives its own count, and the
    one-worker line its count when it differs; a run recorded before the counts were (a setting)
    shows the setting's."""
    two_counts = {'1': {'runs': 10, 'runs_per_min': 50.0, 'cpu_s_per_run': 1.0},
                  '2': {'runs': 100, 'runs_per_min': 101.0, 'cpu_s_per_run': 1.1}}
    measured = {goal: m for goal, _, m, _ in speed_table.rows(run(mc={'deck': two_counts, 'deck_paper': mc(150.0)}))}
    assert measured['Monte Carlo, 300 s `deck`'] == ('101.0 runs/min on 2 workers (100 runs, 1.1 CPU s per run), '
                                                     '50.0 on 1 (10 runs)')
    assert measured['Monte Carlo, 300 s `deck_paper`'] == ('150.0 runs/min on 2 workers (4 runs, 1.2 CPU s per run), '
                                                           '75.0 on 1')
