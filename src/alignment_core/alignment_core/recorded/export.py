"""Samples -> the canonical CSV layout (the importer's inverse): for a worked example from
simulated data and the round-trip tests. Floats are written with repr (shortest text that
reads back to the same float), stamps as exact decimal seconds."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from alignment_core.geometry import earth
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample

from .derive import median_interval_ns
from .layout import CANONICAL


def seconds(t_ns: int) -> str:
    """Exact decimal seconds of a stamp in ns (t_ns >= 0)."""
    return f'{t_ns // 10**9}.{t_ns % 10**9:09d}'


def _row(t_ns: int, values) -> str:
    return ','.join([seconds(int(t_ns)), *(repr(float(v)) for v in values)])


def _write(path: Path, header: list[str], rows: list[str]) -> None:
    Path(path).write_text(','.join(header) + '\n' + '\n'.join(rows) + '\n')


def write_imu(path: Path, imu: list[ImuSample]) -> None:
    """imu.csv: increments over the interval ending at each stamp (the first: the median one)."""
    t = np.array([s.t_ns for s in imu], dtype=np.int64)
    dt = np.r_[median_interval_ns(t), np.diff(t)] * 1e-9
    c = CANONICAL['imu']
    _write(path, [c['time'], *c['gyro'], *c['accel']],
           [_row(s.t_ns, [*(s.gyro * dt[k]), *(s.accel * dt[k])]) for k, s in enumerate(imu)])


def write_master(path: Path, master: list[MasterSample], plane: earth.TangentPlane) -> None:
    """master.csv: attitude (w, x, y, z), ENU velocity, geodetic position (deg, deg, m)."""
    c = CANONICAL['master']
    rows = []
    for s in master:
        lat, lon, h = plane.to_geodetic(s.p_w)
        v_n = quat_to_dcm(s.q_nb) @ s.v_b
        q = s.q_nb
        rows.append(_row(s.t_ns, [q[3], q[0], q[1], q[2], *v_n, np.degrees(lat), np.degrees(lon), h]))
    _write(path, [c['time'], *c['quaternion'], *c['velocity'], *c['position']], rows)


def write_velocity(path: Path, samples: list[LdvSample] | list[DopplerSample], stream: str) -> None:
    """ldv.csv / doppler.csv: velocity and its sigma (-1 and zero velocity: no measurement)."""
    c = CANONICAL[stream]
    rows = []
    for s in samples:
        v = s.v_s if isinstance(s, LdvSample) else s.v_b
        rows.append(_row(s.t_ns, [*v, s.sigma]) if s.valid else _row(s.t_ns, [0.0, 0.0, 0.0, -1.0]))
    _write(path, [c['time'], *c['velocity'], c['sigma']], rows)
