"""The aerospace layout of a log (NED/FRD Euler angles in degrees, rates instead of increments,
specific force in g, times from 0) and its map, written from a simulated run's samples by code
independent of the importer's: for the round-trip tests (in-process and through replay.sh)."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core import pipeline
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.recorded import export
from alignment_core.units import DEG, G0

FRD = np.diag([1.0, -1.0, -1.0])                       # v_FRD = FRD @ v_FLU
NED = np.array([[0, 1.0, 0], [1.0, 0, 0], [0, 0, -1.0]])   # v_NED = NED @ v_ENU
AEROSPACE_MAP = {
    'imu': {'time': 'time', 'kind': 'rates', 'body_axes': 'FRD', 'gyro': ['p', 'q', 'r'], 'gyro_unit': 'deg/s',
            'accel': ['fx', 'fy', 'fz'], 'accel_unit': 'g'},
    'master': {'time': 'time', 'body_axes': 'FRD', 'nav_frame': 'NED', 'attitude': 'ned_frd_321',
               'euler': ['roll', 'pitch', 'yaw'], 'euler_unit': 'deg', 'velocity': ['vn', 've', 'vd'],
               'position': ['lat', 'lon', 'alt']},
    'ldv': {'time': 'time', 'body_axes': 'FRD', 'velocity': ['u', 'v', 'w'], 'sigma': 'sd'},
}


def _t(t_ns: int, t0_ns: int) -> str:
    return export.seconds(t_ns - t0_ns)


def write_rows(path, head: str, rows: list[list]) -> None:
    path.write_text(head + '\n' + '\n'.join(','.join(x if isinstance(x, str) else repr(float(x)) for x in r)
                                            for r in rows) + '\n')


def write_aerospace(d, sc, inp) -> None:
    """The second layout, written here from the samples (not by the importer's code)."""
    plane = pipeline.plane_of(sc)
    t0 = sc.t0_ns                                  # the first stamp: times from 0
    write_rows(d / 'imu.csv', 'time,p,q,r,fx,fy,fz',
               [[_t(s.t_ns, t0), *(FRD @ s.gyro / DEG), *(FRD @ s.accel / G0)] for s in inp.imu])
    rows = []
    for m in inp.master:
        c_ned_frd = NED @ quat_to_dcm(m.q_nb) @ FRD.T
        yaw, pitch, roll = Rotation.from_matrix(c_ned_frd).as_euler('ZYX', degrees=True)
        lat, lon, h = plane.to_geodetic(m.p_w)
        rows.append([_t(m.t_ns, t0), roll, pitch, yaw, *(NED @ quat_to_dcm(m.q_nb) @ m.v_b),
                     np.degrees(lat), np.degrees(lon), h])
    write_rows(d / 'master.csv', 'time,roll,pitch,yaw,vn,ve,vd,lat,lon,alt', rows)
    write_rows(d / 'ldv.csv', 'time,u,v,w,sd',
               [[_t(s.t_ns, t0), *(FRD @ s.v_s), s.sigma] if s.valid else [_t(s.t_ns, t0), '', '', '', '-1']
                for s in inp.ldv])
