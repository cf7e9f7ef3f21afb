"""Each option of a layout map exercised through the reader on data, against values worked out
by hand: Euler conventions setting their own frames, the frame of a body-rate column, velocity
in body axes, NED and inverse quaternions, RFU IMU axes, time units, files without a header
row, .mat master logs, constant sigmas, and the warnings of upside-down axes."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.io import savemat
from scipy.spatial.transform import Rotation

from alignment_core.recorded import recording
from alignment_core.recorded.column_units import LogError
from alignment_core.units import DEG, G0

IMU_HEAD = 't_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps'
DT = 0.01
EULER_MASTER = {'time': 't', 'attitude': 'ned_frd_321', 'euler': ['roll', 'pitch', 'yaw'], 'euler_unit': 'deg',
                'velocity': ['vn', 've', 'vd'], 'position': ['lat', 'lon', 'h']}


def write(path, head: str, rows: list[str]):
    path.write_text(head + '\n' + '\n'.join(rows) + '\n')
    return path


@pytest.fixture
def imu(tmp_path):
    """A level FLU IMU at rest, 100 Hz, from 1.01 s."""
    return write(tmp_path / 'imu.csv', IMU_HEAD,
                 [f'{1 + (k + 1) * DT!r},0.0,0.0,0.0,0.0,0.0,{G0 * DT!r}' for k in range(20)])


def euler_master(tmp_path, extra_head: str = '', extra: str = ''):
    """Heading East, level; 10 m/s North, 1 m/s down (NED columns); at 40 N."""
    return write(tmp_path / 'm.csv', 't,roll,pitch,yaw,vn,ve,vd,lat,lon,h' + extra_head,
                 [f'{1 + k * DT!r},0,0,90,10,0,1,40,116,0' + extra for k in range(21)])


def test_an_euler_convention_sets_the_velocity_and_rate_frames(imu, tmp_path):
    # nose East: North is the FLU left (+y), down is -z; FRD body rate (p, q, r) -> FLU (p, -q, -r)
    m = euler_master(tmp_path, ',p,q,r', ',0.01,0.02,0.03')
    lay = {'master': {**EULER_MASTER, 'body_rate': ['p', 'q', 'r']}}
    log = recording.load(imu, m, layout_map=lay).master
    assert log.v_b[0] == pytest.approx([0.0, 10.0, -1.0], abs=1e-12)
    assert log.w_b[0] == pytest.approx([0.01, -0.02, -0.03], abs=1e-15)
    for key, value in (('nav_frame', 'ENU'), ('body_axes', 'FLU')):
        with pytest.raises(LogError, match=f"master.{key}: '{value}' contradicts attitude 'ned_frd_321'"):
            recording.load(imu, m, layout_map={'master': {**EULER_MASTER, key: value}})
    ok = {'master': {**EULER_MASTER, 'nav_frame': 'NED', 'body_axes': 'FRD'}}     # agreeing: fine
    assert recording.load(imu, m, layout_map=ok).master.v_b[0] == pytest.approx([0.0, 10.0, -1.0], abs=1e-12)


MASTER_HEAD = 't_s,qw,qx,qy,qz,v_e_mps,v_n_mps,v_u_mps,lat_deg,lon_deg,h_m'
H = float(np.sqrt(0.5))


def test_a_body_rate_column_wrt_inertial_space_loses_the_earth_and_transport_rates(imu, tmp_path):
    # heading North (90 deg about up): body x = North, y = West, z = Up; at 40 N, 100 m, v = (20, 30, 0) ENU
    lat, h, v_e, v_n, omega = 40 * DEG, 100.0, 20.0, 30.0, 7.292115e-5
    e2 = (1 / 298.257223563) * (2 - 1 / 298.257223563)
    s2 = np.sin(lat) ** 2
    r_n, r_m = 6378137.0 / np.sqrt(1 - e2 * s2), 6378137.0 * (1 - e2) / (1 - e2 * s2) ** 1.5
    w_in = np.array([-v_n / (r_m + h), omega * np.cos(lat) + v_e / (r_n + h),
                     omega * np.sin(lat) + v_e * np.tan(lat) / (r_n + h)])      # E, N, U
    w_nb = np.array([0.001, 0.002, 0.003])
    w_ib = (w_nb + np.array([w_in[1], -w_in[0], w_in[2]])).tolist()   # body x, y, z
    m = write(tmp_path / 'm.csv', MASTER_HEAD + ',wx,wy,wz',
              [f'{1 + k * DT!r},{H!r},0,0,{H!r},{v_e},{v_n},0,40,116,{h},{w_ib[0]!r},{w_ib[1]!r},{w_ib[2]!r}'
               for k in range(21)])
    lay = {'master': {'body_rate': ['wx', 'wy', 'wz'], 'body_rate_frame': 'ib'}}
    got = recording.load(imu, m, layout_map=lay).master
    assert not got.rate_derived and got.w_b[0] == pytest.approx(w_nb, abs=1e-15)
    lay['master']['body_rate_frame'] = 'nb'                  # the default: the column as it is
    assert recording.load(imu, m, layout_map=lay).master.w_b[0] == pytest.approx(w_ib, abs=1e-18)
    lay['master']['body_rate_frame'] = 'ie'
    with pytest.raises(LogError, match="body_rate_frame: 'ie': expected nb"):
        recording.load(imu, m, layout_map=lay)


def test_upside_down_axes_are_warned(imu, tmp_path):
    frd = write(tmp_path / 'frd.csv', IMU_HEAD, [f'{1 + (k + 1) * DT!r},0,0,0,0,0,{-G0 * DT!r}' for k in range(20)])
    m = write(tmp_path / 'm.csv', MASTER_HEAD, [f'{1 + k * DT!r},1,0,0,0,0,0,0,40,116,0' for k in range(21)])
    log = recording.load(frd, m)          # FRD increments declared FLU: |f| = g passes, f_z = -g does not
    assert any('body up axis -9.807 m/s^2: the axes point down' in w for w in log.imu.report.warnings)
    assert recording.load(frd, m, layout_map={'imu': {'body_axes': 'FRD'}}).imu.report.warnings == []
    # a level FRD-in-NED quaternion (identity) declared FLU in NED: the body's up axis points down
    lay = {'master': {'nav_frame': 'NED'}}
    assert any('body up axis points down' in w for w in recording.load(imu, m, layout_map=lay).master.report.warnings)
    lay = {'master': {'nav_frame': 'NED', 'body_axes': 'FRD'}}
    assert recording.load(imu, m, layout_map=lay).master.report.warnings == []


def turning_master(tmp_path, rate: float = 0.05):
    """Level, turning about up at `rate` rad/s, 100 Hz, 2 s."""
    half = [rate * k * DT / 2 for k in range(201)]
    rows = [f'{1 + k * DT!r},{float(np.cos(a))!r},0,0,{float(np.sin(a))!r},0,0,0,40,116,0' for k, a in enumerate(half)]
    return write(tmp_path / 'turn.csv', MASTER_HEAD, rows)


def test_slave_rates_far_from_the_masters_are_warned(tmp_path):
    m = turning_master(tmp_path)       # 0.05 rad/s = 2.86 deg/s: under the 3 rad/s limit when read as rad/s
    head = 't,gx,gy,gz,ax,ay,az'
    deg = write(tmp_path / 'd.csv', head, [f'{1 + k * DT!r},0,0,{0.05 / DEG!r},0,0,1' for k in range(1, 201)])
    lay = {'imu': {'time': 't', 'kind': 'rates', 'gyro': ['gx', 'gy', 'gz'], 'accel': ['ax', 'ay', 'az'],
                   'accel_unit': 'g'}}
    w = recording.load(deg, m, layout_map=lay).imu.report.warnings
    assert len(w) == 1 and 'rms rate 57.3 times the master' in w[0] and 'deg/s given as rad/s?' in w[0]
    rad = write(tmp_path / 'r.csv', head, [f'{1 + k * DT!r},0,0,0.05,0,0,1' for k in range(1, 201)])
    lay['imu']['gyro_unit'] = 'deg/s'
    w = recording.load(rad, m, layout_map=lay).imu.report.warnings
    assert len(w) == 1 and 'rad/s given as deg/s?' in w[0]
    del lay['imu']['gyro_unit']
    log = recording.load(rad, m, layout_map=lay)
    assert log.imu.report.warnings == []
    assert log.master.rate_derived and log.master.w_b == pytest.approx(np.tile([0, 0, 0.05], (201, 1)), abs=1e-12)


def test_times_in_ms_declared_as_seconds_are_warned(tmp_path):
    imu = write(tmp_path / 'i.csv', IMU_HEAD, [f'{1000 + (k + 1) * 10},0,0,0,0,0,{G0 * DT!r}' for k in range(20)])
    m = write(tmp_path / 'm.csv', MASTER_HEAD, [f'{1000 + k * 10},1,0,0,0,0,0,0,40,116,0' for k in range(21)])
    w = recording.load(imu, m).imu.report.warnings
    assert any('median spacing 10 s (0.1 Hz) after conversion from s: is time_unit right' in x for x in w)
    log = recording.load(imu, m, layout_map={'imu': {'time_unit': 'ms'}, 'master': {'time_unit': 'ms'}})
    assert log.imu.report.warnings == [] and log.imu.t_ns[0] == 1_010_000_000
    assert log.imu.accel[0, 2] == pytest.approx(G0)


def test_rates_sampled_at_the_stamps_become_interval_means(tmp_path):
    # a rate linear in time, w(t) = 0.01 + 0.5 (t - 1) rad/s, sampled at t_k: its mean over
    # (t_k - dt, t_k] is w(t_k - dt / 2); RFU axes: the x column is the FLU -y, the y column FLU +x
    m = write(tmp_path / 'm.csv', MASTER_HEAD, [f'{1 + k * DT!r},1,0,0,0,0,0,0,40,116,0' for k in range(21)])
    t = (1 + DT * np.arange(1, 21)).tolist()
    w = [0.01 + 0.5 * (x - 1) for x in t]
    path = write(tmp_path / 'i.csv', 't,wx,wy,wz,ax,ay,az', [f'{t[k]!r},{w[k]!r},0,0,0,0,{G0!r}' for k in range(20)])
    lay = {'imu': {'time': 't', 'kind': 'rates', 'rate_sampling': 'instant', 'body_axes': 'RFU',
                   'gyro': ['wx', 'wy', 'wz'], 'accel': ['ax', 'ay', 'az']}}
    gyro = recording.load(path, m, layout_map=lay).imu.gyro
    assert gyro[1:, 1] == pytest.approx([-(0.01 + 0.5 * (x - DT / 2 - 1)) for x in t[1:]], rel=1e-12)
    assert gyro[0, 1] == pytest.approx(-w[0]) and np.all(gyro[:, [0, 2]] == 0.0)     # the first: as sampled
    lay['imu']['rate_sampling'] = 'mean'                                  # the default: taken as they are
    assert recording.load(path, m, layout_map=lay).imu.gyro[:, 1] == pytest.approx([-x for x in w], rel=1e-15)


def docs_map(word: str) -> dict:
    """The example map of docs/own-data.md that contains `word`."""
    import re
    from pathlib import Path

    import yaml
    text = (Path(__file__).resolve().parents[2] / 'docs/own-data.md').read_text()
    blocks = [b for b in re.findall(r'```yaml\n(.*?)```', text, re.S) if word in b]
    assert len(blocks) == 1
    return yaml.safe_load(blocks[0])


def test_the_docs_papers_map_on_space_delimited_files_without_a_header(tmp_path):
    # RFU increments in arcsec: 0.36" per 10 ms about the forward (RFU y) axis = FLU x, 36"/s
    imu = tmp_path / 'imu.txt'
    imu.write_text(''.join(f'{1 + (k + 1) * DT!r} 0 0.36 0 0 0 {G0 * DT!r}\n' for k in range(20)))
    # pitch 10, roll 0, yaw 30 deg (north-west positive): the nose 30 deg West of North, 10 deg up;
    # the file holds pitch, roll, yaw (the map reorders them); ENU velocity (1, 2, 3)
    master = tmp_path / 'master.txt'
    master.write_text(''.join(f'{1 + k * DT!r}  10 0 30  1 2 3  40 116 5\n' for k in range(21)))
    lay = docs_map('enu_rfu_312')
    log = recording.load(imu, master, layout_map=lay)
    assert log.imu.gyro[0] == pytest.approx([36 * DEG / 3600, 0, 0], rel=1e-12, abs=1e-18)
    assert log.imu.accel[0] == pytest.approx([0, 0, G0], rel=1e-12)
    th, ps = 10 * DEG, 30 * DEG
    nose = np.array([-np.sin(ps) * np.cos(th), np.cos(ps) * np.cos(th), np.sin(th)])
    c = Rotation.from_quat(log.master.q_nb[0]).as_matrix()
    assert c[:, 0] == pytest.approx(nose, abs=1e-15)
    assert log.master.v_b[0, 0] == pytest.approx(nose @ [1.0, 2.0, 3.0], abs=1e-12)
    assert (log.master.lat[0], log.master.h[0]) == pytest.approx((40 * DEG, 5.0))
    lay['master']['yaw_negated'] = True        # a clockwise heading: 30 deg East of North
    c = Rotation.from_quat(recording.load(imu, master, layout_map=lay).master.q_nb[0]).as_matrix()
    assert c[:, 0] == pytest.approx([np.sin(ps) * np.cos(th), np.cos(ps) * np.cos(th), np.sin(th)], abs=1e-15)


def test_the_docs_mat_map_on_mat_files(tmp_path):
    t = 1.0 + DT * np.arange(21)
    # IMU matrix: t, gyro deg/s, accel g, FRD: 0.1 deg/s about forward, 1 g up (FRD z = -1 g)
    savemat(tmp_path / 'imu.mat', {'IMU': np.column_stack([t[1:], np.tile([0.1, 0, 0, 0, 0, -1.0], (20, 1))])})
    # master vectors: FRD-in-NED quaternion of heading East (90 deg about down), NED velocity (10, 0, 1)
    h = float(np.sqrt(0.5))
    cols = {'t': t, 'q0': np.full(21, h), 'q1': np.zeros(21), 'q2': np.zeros(21), 'q3': np.full(21, h),
            'vn': np.full(21, 10.0), 've': np.zeros(21), 'vd': np.ones(21),
            'lat': np.full(21, 40.0), 'lon': np.full(21, 116.0), 'h': np.zeros(21)}
    savemat(tmp_path / 'master.mat', cols)
    log = recording.load(tmp_path / 'imu.mat', tmp_path / 'master.mat', layout_map=docs_map('variable: IMU'))
    assert log.imu.gyro[0] == pytest.approx([0.1 * DEG, 0, 0], abs=1e-18)
    assert log.imu.accel[0] == pytest.approx([0, 0, G0], abs=1e-12)
    assert Rotation.from_quat(log.master.q_nb[0]).as_matrix() == pytest.approx(np.eye(3), abs=1e-15)  # FLU = ENU
    assert log.master.v_b[0] == pytest.approx([0.0, 10.0, -1.0], abs=1e-12)
    assert log.imu.report.warnings == [] and log.master.report.warnings == []


def test_an_inverse_quaternion_and_a_body_frame_velocity(imu, tmp_path):
    # C_n^b of heading North (90 deg about up): its conjugate (h, 0, 0, -h); body velocity (5, 0.5, 0) FLU
    m = write(tmp_path / 'm.csv', MASTER_HEAD, [f'{1 + k * DT!r},{H!r},0,0,{-H!r},5,0.5,0,40,116,0' for k in range(21)])
    lay = {'master': {'quaternion_inverse': True, 'velocity_frame': 'body'}}
    log = recording.load(imu, m, layout_map=lay).master
    assert Rotation.from_quat(log.q_nb[0]).as_matrix()[:, 0] == pytest.approx([0.0, 1.0, 0.0], abs=1e-15)
    assert log.v_b[0] == pytest.approx([5.0, 0.5, 0.0], abs=1e-15)
    m = write(tmp_path / 'm.csv', MASTER_HEAD, [f'{1 + k * DT!r},1,0,0,0,0,0,0,0.7,116,0' for k in range(21)])
    with pytest.raises(LogError, match='longitude beyond 360 deg after conversion from rad'):   # 116 rad
        recording.load(imu, m, layout_map={'master': {'position_unit': 'rad'}})
