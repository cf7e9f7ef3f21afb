"""import_log: a simulated run's sensor streams exported to the canonical CSV layout and to a
second one (aerospace NED/FRD Euler angles in degrees, rates instead of increments, specific
force in g, times from 0), imported into bags, fed to a fresh filter: the estimates equal the
original run's to 1e-6 rad (what is lost: the master's body rate, derived from its attitudes,
and the last digits of the conversions). Plus the bag's metadata, the importer's errors and a
replay of a bag without /ldv/twist."""
from __future__ import annotations

import numpy as np
import pytest
import yaml
from rclpy.serialization import deserialize_message
from support.recorded_layouts import AEROSPACE_MAP, write_aerospace

from alignment_core import pipeline
from alignment_core.config import scenario as core_scenario
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.recorded import export, recording
from alignment_core.units import DEG
from alignment_ros import convert, importer, topics
from alignment_ros.bag import BagReader
from alignment_ros.replay import replay_topics

SETS = ['duration_s=14.0', 'aircraft.catapult.launch_time_s=8.0']


@pytest.fixture(scope='module')
def run():
    sc = core_scenario.load('catapult_paper', core_scenario.parse_overrides(SETS))
    inp = pipeline.simulate(sc)
    return sc, inp, pipeline.align(sc, inp)


def write_canonical(d, sc, inp) -> None:
    export.write_imu(d / 'imu.csv', inp.imu)
    export.write_master(d / 'master.csv', inp.master, pipeline.plane_of(sc))
    export.write_velocity(d / 'ldv.csv', inp.ldv, 'ldv')


def align_bag(bag, sc) -> TransferAlignment:
    """A fresh filter fed the bag's sensor messages in stamp order (as the filter node takes them)."""
    meta = BagReader(bag).metadata().custom_data
    plane = recording.plane_at((float(meta[importer.ORIGIN_LAT]) * DEG, float(meta[importer.ORIGIN_LON]) * DEG))
    f = TransferAlignment(sc.filter, plane, float(meta[importer.IMU_RATE]))
    push = {topics.AIRCRAFT_IMU: (f.push_imu, convert.msg_to_imu),
            topics.MASTER_ODOM: (f.push_master, convert.msg_to_master),
            topics.LDV_TWIST: (f.push_ldv, convert.msg_to_ldv)}
    for m in BagReader(bag).messages(list(push)):
        fn, conv = push[m.topic]
        fn(conv(deserialize_message(m.data, topics.msg_class(m.type_name))))
        f.process()
    f.process(final=True)
    return f


@pytest.mark.parametrize('layout', ['canonical', 'aerospace'])
def test_round_trip_reproduces_the_estimates(run, tmp_path, layout):
    sc, inp, original = run
    args = []
    if layout == 'canonical':
        write_canonical(tmp_path, sc, inp)
    else:
        write_aerospace(tmp_path, sc, inp)
        (tmp_path / 'map.yaml').write_text(yaml.safe_dump(AEROSPACE_MAP))
        args = ['--map', str(tmp_path / 'map.yaml')]
    bag = tmp_path / 'bag'
    assert importer.main(['--imu', str(tmp_path / 'imu.csv'), '--master', str(tmp_path / 'master.csv'),
                          '--ldv', str(tmp_path / 'ldv.csv'), '--out', str(bag), *args]) == 0
    meta = BagReader(bag).metadata().custom_data
    assert meta[importer.TIME_OFFSET] == ('0' if layout == 'canonical' else str(sc.t0_ns))
    assert float(meta[importer.IMU_RATE]) == sc.rate_hz
    assert meta['import.imu_rows'] == str(len(inp.imu)) and meta['import.master_rows_skipped_nan'] == '0'
    counts = BagReader(bag).counts()
    assert counts[topics.AIRCRAFT_IMU] == len(inp.imu) and counts[topics.LDV_TWIST] == len(inp.ldv)
    f = align_bag(bag, sc)
    a = np.array([e.misalignment for e in original.outputs])
    b = np.array([e.misalignment for e in f.outputs])
    assert [e.t_ns for e in f.outputs] == [e.t_ns for e in original.outputs]
    assert np.max(np.abs(a - b)) < 1e-6
    assert np.max(np.abs(a[-1])) > 100 * 1e-6            # a real estimate (tens of arcmin)


def test_importer_errors_exit_2_with_one_message(run, tmp_path, capsys):
    sc, inp, _ = run
    write_canonical(tmp_path, sc, inp)
    text = (tmp_path / 'master.csv').read_text().replace('v_u_mps', 'v_up')
    (tmp_path / 'bad.csv').write_text(text)
    assert importer.main(['--imu', str(tmp_path / 'imu.csv'), '--master', str(tmp_path / 'bad.csv'),
                          '--out', str(tmp_path / 'bag')]) == 2
    assert "no column named 'v_u_mps'" in capsys.readouterr().err
    assert not (tmp_path / 'bag').exists()
    (tmp_path / 'map.yaml').write_text('imu: [1, 2]\n')
    assert importer.main(['--imu', str(tmp_path / 'imu.csv'), '--master', str(tmp_path / 'master.csv'),
                          '--map', str(tmp_path / 'map.yaml'), '--out', str(tmp_path / 'bag')]) == 2
    assert 'map: imu: expected a mapping' in capsys.readouterr().err


def test_a_bag_without_ldv_plays_what_it_has():
    play, wait = replay_topics({topics.CLOCK: '', topics.MASTER_ODOM: '', topics.AIRCRAFT_IMU: ''}, {})
    assert topics.LDV_TWIST not in play and f'{topics.LDV_TWIST}=1' not in wait
    assert set(play) == {topics.CLOCK, topics.MASTER_ODOM, topics.AIRCRAFT_IMU}


def test_a_doppler_log_becomes_its_topic(run, tmp_path):
    sc, inp, _ = run
    write_canonical(tmp_path, sc, inp)
    (tmp_path / 'doppler.csv').write_text('t_s,v_x_mps,v_y_mps,v_z_mps,sigma_mps\n'
                                          '1.5,0.1,0.2,0.3,0.05\n1.6,,,,-1\n1.7,0.1,0.2,0.3,0.05\n')
    assert importer.main(['--imu', str(tmp_path / 'imu.csv'), '--master', str(tmp_path / 'master.csv'),
                          '--doppler', str(tmp_path / 'doppler.csv'), '--out', str(tmp_path / 'bag')]) == 0
    msgs = [deserialize_message(m.data, topics.msg_class(m.type_name))
            for m in BagReader(tmp_path / 'bag').messages([topics.DOPPLER_TWIST])]
    assert [m.header.frame_id for m in msgs] == [topics.FRAME_AIRCRAFT] * 3
    d = [convert.msg_to_doppler(m) for m in msgs]
    assert [s.valid for s in d] == [True, False, True] and d[0].sigma == pytest.approx(0.05)
    assert list(d[2].v_b) == [0.1, 0.2, 0.3] and d[0].t_ns == 1_500_000_000
    assert topics.LDV_TWIST not in BagReader(tmp_path / 'bag').topics()


def test_the_docs_aerospace_map_reads_the_aerospace_layout(run, tmp_path):
    # the docs' example map (frames from the convention, one LDV sigma for every row) on the
    # aerospace files: the same streams as the tests' map, the LDV sigma the scenario's 0.01 m/s
    import re
    from pathlib import Path
    sc, inp, _ = run
    write_aerospace(tmp_path, sc, inp)
    text = (Path(__file__).resolve().parents[2] / 'docs/own-data.md').read_text()
    docs = yaml.safe_load(next(b for b in re.findall(r'```yaml\n(.*?)```', text, re.S) if 'ned_frd_321' in b))
    files = (tmp_path / 'imu.csv', tmp_path / 'master.csv', tmp_path / 'ldv.csv')
    a, b = recording.load(*files, layout_map=docs), recording.load(*files, layout_map=AEROSPACE_MAP)
    for name in ('gyro', 'accel'):
        assert np.array_equal(getattr(a.imu, name), getattr(b.imu, name))
    for name in ('q_nb', 'v_b', 'w_b', 'lat', 'lon', 'h'):
        assert np.array_equal(getattr(a.master, name), getattr(b.master, name))
    # rows without a measurement (empty cells after the launch) are skipped and counted under one sigma
    assert np.array_equal(a.ldv.t_ns, b.ldv.t_ns[b.ldv.valid]) and a.ldv.report.skipped == np.sum(~b.ldv.valid)
    assert np.array_equal(a.ldv.v, b.ldv.v[b.ldv.valid]) and np.all(a.ldv.sigma == 0.01)
    assert [r.warnings for r in a.reports()] == [[], [], []]
