"""Each option of a layout map exercised through the reader on data, against values worked out
by hand: Euler conventions setting their own frames, the frame of a body-rate column, velocity
in body axes, NED and inverse quaternions, RFU IMU axes, time units, files without a header
row, .mat master logs, constant sigmas, and the warnings of upside-down axes."""
from __future__ import annotations

import numpy as np
import pytest

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
