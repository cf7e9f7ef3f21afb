"""Each option of a layout map exercised through the reader on data, against values worked out
by hand: Euler conventions setting their own frames, the frame of a body-rate column, velocity
in body axes, NED and inverse quaternions, RFU IMU axes, time units, files without a header
row, .mat master logs, constant sigmas, and the warnings of upside-down axes."""
from __future__ import annotations

import pytest

from alignment_core.recorded import recording
from alignment_core.recorded.column_units import LogError
from alignment_core.units import G0

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
