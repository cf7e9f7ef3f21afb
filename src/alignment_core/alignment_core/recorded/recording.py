"""A whole recording: the IMU and master INS logs (and LDV / Doppler radar, when given) on one
time base, converted to the samples the filter takes.

Time base: with `time_offset_s: auto`, times that start at or below 0 (a log's "time from
start") are shifted so that the earliest stamp of all streams is 1 s (ROS reads a stamp of 0
as "no time"); times above 0 (absolute ones) are kept. A number shifts every stamp by it.
World positions are in the ENU tangent plane at `origin` (lat, lon rad; height 0), by default
the first master fix.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from alignment_core.geometry import earth
from alignment_core.samples import DopplerSample, ImuSample, LdvSample, MasterSample

from .column_units import LogError
from .layout import read_map
from .streams import ImuLog, MasterLog, StreamReport, VelocityLog, read_imu, read_master, read_velocity

START_NS = 1_000_000_000     # where times from 0 start (the scenarios' start_time_s)
MIN_MASTER_RATE_RADPS = 5e-3     # a master moving this much (rms) tells the slave's rate unit
RATE_RATIO = 10.0                # slave / master rms rate beyond this factor: warned
DEG_PER_RAD = 180.0 / np.pi


@dataclass
class RecordedLog:
    imu: ImuLog
    master: MasterLog
    ldv: VelocityLog | None
    doppler: VelocityLog | None
    time_offset_ns: int

    def reports(self) -> list[StreamReport]:
        return [s.report for s in (self.imu, self.master, self.ldv, self.doppler) if s is not None]


def load(imu: Path, master: Path, ldv: Path | None = None, doppler: Path | None = None,
         layout_map: dict[str, Any] | None = None) -> RecordedLog:
    """Read and convert the logs (`layout_map`: a map's contents; None: the canonical layout)."""
    lay, offset = read_map(layout_map)
    streams: dict[str, Any] = {
        'imu': read_imu(Path(imu), lay['imu']),
        'master': read_master(Path(master), lay['master']),
        'ldv': read_velocity('ldv', Path(ldv), lay['ldv']) if ldv is not None else None,
        'doppler': read_velocity('doppler', Path(doppler), lay['doppler']) if doppler is not None else None,
    }
    given = [s for s in streams.values() if s is not None]
    _compare_rates(streams['imu'], streams['master'])
    _check_overlap({k: s for k, s in streams.items() if s is not None})
    if offset == 'auto':
        first = min(int(s.t_ns[0]) for s in given)
        offset_ns = START_NS - first if first <= 0 else 0
    else:
        offset_ns = int(round(float(offset) * 1e9))
    for s in given:
        s.t_ns = s.t_ns + offset_ns
        if s.t_ns[0] <= 0:
            raise LogError(f'{s.report.source}: stamps at or below 0 after the time offset '
                           f'{offset_ns * 1e-9:g} s (first {s.t_ns[0] * 1e-9:g} s)')
    return RecordedLog(streams['imu'], streams['master'], streams['ldv'], streams['doppler'], offset_ns)


def _check_overlap(streams: dict[str, Any]) -> None:
    """LogError when two streams' time spans do not overlap (different time bases: one absolute,
    one from 0, or another unit)."""
    spans = {k: (int(s.t_ns[0]), int(s.t_ns[-1])) for k, s in streams.items()}
    ref = spans['master']
    for k, (a, b) in spans.items():
        if b < ref[0] or a > ref[1]:
            raise LogError(f'{k} times {a * 1e-9:.9g} .. {b * 1e-9:.9g} s and master times '
                           f'{ref[0] * 1e-9:.9g} .. {ref[1] * 1e-9:.9g} s do not overlap: different time '
                           f'bases or units?')


def _compare_rates(imu: ImuLog, master: MasterLog) -> None:
    """Warn when the slave's rates are far from the master's (a moving master: deg/s given as
    rad/s shows as about 57.3 times, rad/s as deg/s as 1/57.3)."""
    w_master = float(np.sqrt(np.mean(np.sum(master.w_b**2, axis=1))))
    if w_master < MIN_MASTER_RATE_RADPS:
        return
    ratio = float(np.sqrt(np.mean(np.sum(imu.gyro**2, axis=1)))) / w_master
    if not 1 / RATE_RATIO <= ratio <= RATE_RATIO:
        log_ratio = np.log(ratio) if ratio > 0.0 else -np.inf
        hint = ('deg/s given as rad/s?' if abs(log_ratio - np.log(DEG_PER_RAD)) < np.log(2.0) else
                'rad/s given as deg/s?' if abs(log_ratio + np.log(DEG_PER_RAD)) < np.log(2.0) else
                'are the units right?')
        imu.report.warnings.append(f'gyro: rms rate {ratio:.4g} times the master\'s ({w_master:.3g} rad/s): {hint}')


def origin_of(log: RecordedLog) -> tuple[float, float]:
    """The default world origin: the first master fix (lat, lon, rad)."""
    return float(log.master.lat[0]), float(log.master.lon[0])


def imu_samples(log: RecordedLog) -> list[ImuSample]:
    i = log.imu
    return [ImuSample(int(t), i.gyro[k], i.accel[k]) for k, t in enumerate(i.t_ns)]


def master_samples(log: RecordedLog, plane: earth.TangentPlane) -> list[MasterSample]:
    m = log.master
    p_w = plane.from_geodetic(m.lat, m.lon, m.h)
    return [MasterSample(int(t), p_w[k], m.q_nb[k], m.v_b[k], m.w_b[k]) for k, t in enumerate(m.t_ns)]


def ldv_samples(v: VelocityLog) -> list[LdvSample]:
    return [LdvSample(int(t), v.v[k], float(v.sigma[k]), bool(v.valid[k])) for k, t in enumerate(v.t_ns)]


def doppler_samples(v: VelocityLog) -> list[DopplerSample]:
    return [DopplerSample(int(t), v.v[k], float(v.sigma[k]), bool(v.valid[k])) for k, t in enumerate(v.t_ns)]


def plane_at(origin: tuple[float, float]) -> earth.TangentPlane:
    """The world tangent plane at `origin` (lat, lon rad), height 0 (as the scenarios' is)."""
    return earth.TangentPlane(origin[0], origin[1], 0.0)


def stamps_ns(log: RecordedLog) -> np.ndarray:
    """Every stream's stamps, sorted and unique (the /clock ticks)."""
    return np.unique(np.concatenate([s.t_ns for s in (log.imu, log.master, log.ldv, log.doppler) if s is not None]))
