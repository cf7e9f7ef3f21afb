"""The replay's parameters: --set, a params file, the importer's metadata, the data (the first
/master/fix, the IMU stamp spacing), in that order; bad values refused before any node starts."""
from __future__ import annotations

import pytest
from rclpy.serialization import serialize_message

from alignment_core.samples import ImuSample
from alignment_core.validation import ConfigError
from alignment_ros import convert, importer, topics
from alignment_ros.bag_writer import BagWriter
from alignment_ros.replay_params import replay_parameters

HEAD_IMU = 't_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps'
HEAD_MASTER = 't_s,qw,qx,qy,qz,v_e_mps,v_n_mps,v_u_mps,lat_deg,lon_deg,h_m'


@pytest.fixture(scope='module')
def imported(tmp_path_factory):
    d = tmp_path_factory.mktemp('imp')
    (d / 'imu.csv').write_text(HEAD_IMU + '\n' + '\n'.join(
        f'{k * 0.005!r},0.0,0.0,0.0,0.0,0.0,{9.8 * 0.005!r}' for k in range(1, 41)) + '\n')
    (d / 'master.csv').write_text(HEAD_MASTER + '\n' + '\n'.join(
        f'{k * 0.02!r},1.0,0.0,0.0,0.0,0.0,0.0,0.0,{-33.5 + 1e-7 * k!r},151.25,3.0' for k in range(11)) + '\n')
    assert importer.main(['--imu', str(d / 'imu.csv'), '--master', str(d / 'master.csv'), '--out', str(d / 'bag')]) == 0
    return d / 'bag'


@pytest.fixture(scope='module')
def recorded_elsewhere(tmp_path_factory):
    """A bag with the sensor topics and /master/fix, no importer metadata and no params file."""
    path = tmp_path_factory.mktemp('rec') / 'bag'
    with BagWriter(path) as w:
        for t in (topics.AIRCRAFT_IMU, topics.MASTER_FIX):
            w.add_topic(t, topics.TOPIC_TYPES[t])
        for k in range(1, 21):
            t_ns = 10**9 + k * 2_500_000
            w.write(topics.AIRCRAFT_IMU, serialize_message(convert.imu_to_msg(
                ImuSample(t_ns, [0.0] * 3, [0.0, 0.0, 9.8]), 0.0, 0.0)), t_ns)
        fix = convert.navsatfix(10**9, topics.FRAME_SHIP, 0.5, -1.0, 10.0)
        w.write(topics.MASTER_FIX, serialize_message(fix), 10**9)
    return path


def test_an_imported_bag_gives_its_origin_and_rate(imported):
    given, notes = replay_parameters(imported, None, [])
    assert given == {'ship.lat_deg': -33.5, 'ship.lon_deg': 151.25, 'rate_hz': 200.0}
    assert len(notes) == 2 and "the importer's (bag metadata)" in notes[0]


def test_set_wins_and_a_different_origin_is_said(imported):
    given, notes = replay_parameters(imported, None, ['rate_hz=400.0', 'ship.lat_deg=-33.0',
                                                      'ship.lon_deg=151.0', 'filter.model=vm15'])
    assert given == {'rate_hz': 400.0, 'ship.lat_deg': -33.0, 'ship.lon_deg': 151.0, 'filter.model': 'vm15'}
    assert notes == ["the bag's positions are relative to the origin -33.500000000, 151.250000000 deg; "
                     "the filter is given -33.0, 151.0"]


def test_a_params_file_gives_the_filter_but_may_not_contradict_the_import(imported, tmp_path):
    p = tmp_path / 'p.yaml'
    p.write_text('/**:\n  ros__parameters:\n    filter.model: vm15\n')
    given, notes = replay_parameters(imported, p, [])
    assert given == {'filter.model': 'vm15', 'ship.lat_deg': -33.5, 'ship.lon_deg': 151.25, 'rate_hz': 200.0}
    assert len(notes) == 2
    p.write_text('/**:\n  ros__parameters:\n    rate_hz: 200.0\n    ship.lat_deg: -33.5\n    ship.lon_deg: 151.25\n')
    assert replay_parameters(imported, p, [])[0]['rate_hz'] == 200.0            # agreeing: taken
    p.write_text('/**:\n  ros__parameters:\n    rate_hz: 50.0\n    filter.model: vm15\n')
    with pytest.raises(ValueError, match=r'gives rate_hz 50.0 but the imported IMU log runs at 200 Hz'):
        replay_parameters(imported, p, [])
    assert replay_parameters(imported, p, ['rate_hz=50.0'])[0]['rate_hz'] == 50.0   # --set: knowingly
    p.write_text('/**:\n  ros__parameters:\n    ship.lat_deg: 40.0\n    ship.lon_deg: 116.0\n')
    with pytest.raises(ValueError, match=r"gives ship.lat_deg 40.0 but the imported bag's positions are relative"):
        replay_parameters(imported, p, [])


def test_without_metadata_or_params_the_data_gives_them(recorded_elsewhere):
    given, notes = replay_parameters(recorded_elsewhere, None, [])
    assert given['rate_hz'] == 400.0
    assert given['ship.lat_deg'] == pytest.approx(28.64788975654116) and given['ship.lon_deg'] < 0   # 0.5 rad
    assert any('the first /master/fix' in n for n in notes) and any('stamp spacing' in n for n in notes)


def test_bad_values_are_refused(imported):
    with pytest.raises(ConfigError):
        replay_parameters(imported, None, ['filter.model=nonesuch'])
    with pytest.raises(ConfigError, match='--set expects KEY=VALUE'):
        replay_parameters(imported, None, ['rate_hz'])


def test_replay_exits_2_on_a_params_file_contradicting_the_import(imported, tmp_path, capsys):
    from alignment_ros import replay
    p = tmp_path / 'p.yaml'
    p.write_text('/**:\n  ros__parameters:\n    rate_hz: 100.0\n')
    assert replay.main([str(imported), '--params-file', str(p), '--out', str(tmp_path / 'out')]) == 2
    err = capsys.readouterr().err
    assert 'replay:' in err and 'gives rate_hz 100.0 but the imported IMU log runs at 200 Hz' in err
    assert not (tmp_path / 'out' / 'bag').exists()
