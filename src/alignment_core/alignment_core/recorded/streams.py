"""One log file + its layout -> the stream in the project's units, axes and conventions.

Rows with a NaN (or empty cell) in a column the layout uses are skipped and counted (an LDV
or Doppler row whose sigma is negative, no measurement, may leave its velocity empty); a time
that does not increase is an error naming the lines; a column whose magnitude suggests
another unit, or axes that point down, give a warning (the conversion still follows the
layout). A skipped IMU row's interval stays a gap: the next row keeps its own interval.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from alignment_core.geometry import earth
from alignment_core.units import G0

from . import conventions, derive
from .column_units import LogError, factor
from .table import Table, read_table

MAX_RATE_RADPS = 3.0        # a larger body rate (p99) suggests deg/s given as rad/s
SPECIFIC_FORCE_MPS2 = (4.0, 20.0)   # the median |f| near the ground: about 9.8
MAX_SPEED_MPS = 400.0
IMU_SPACING_S = (1e-4, 1.0)     # an IMU runs at 1 Hz to 10 kHz
LISTED = 5                  # line numbers quoted in a message


@dataclass
class StreamReport:
    """What reading a stream did: its file, rows kept, rows skipped (NaN) and where, warnings."""
    source: str
    rows: int = 0
    skipped: int = 0
    skipped_lines: list[int] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def lines(self) -> list[str]:
        out = [f'{self.source}: {self.rows} rows']
        if self.skipped:
            where = ', '.join(map(str, self.skipped_lines)) + (' ...' if self.skipped > LISTED else '')
            out[0] += f', {self.skipped} skipped (NaN or empty cells: lines/rows {where})'
        return out + [f'  warning: {w}' for w in self.warnings]


@dataclass
class ImuLog:
    """t_ns (N,); gyro, accel (N, 3): mean rate (rad/s) and specific force (m/s^2) over the
    interval ending at t_ns, body FLU."""
    t_ns: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    report: StreamReport


@dataclass
class MasterLog:
    """t_ns (N,); q_nb (N, 4) (x, y, z, w) FLU in ENU; v_b (N, 3) ground velocity in body
    axes; w_b (N, 3) body rate w.r.t. ENU (`rate_derived`: from attitude differences);
    lat, lon (N,) rad, h (N,) m."""
    t_ns: np.ndarray
    q_nb: np.ndarray
    v_b: np.ndarray
    w_b: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    h: np.ndarray
    rate_derived: bool
    report: StreamReport


@dataclass
class VelocityLog:
    """t_ns (N,); v (N, 3) m/s in the stream's FLU axes (ship for the LDV, aircraft for the
    Doppler radar); sigma (N,) m/s; valid (N,) False where the log has no measurement."""
    t_ns: np.ndarray
    v: np.ndarray
    sigma: np.ndarray
    valid: np.ndarray
    report: StreamReport


class _Reader:
    """The columns of one stream, NaN rows dropped, times checked."""

    def __init__(self, stream: str, path: Path, lay: dict[str, Any]) -> None:
        self.stream = stream
        self.lay = lay
        self.table: Table = read_table(path, header=bool(lay['header']), delimiter=lay['delimiter'],
                                       variable=lay['variable'], names=lay['names'])
        self.report = StreamReport(str(path))
        self.cols: dict[str, np.ndarray] = {}
        self.interval_ns = np.zeros(0, dtype=np.int64)
        self.previous_kept = np.zeros(0, dtype=bool)

    def take(self, key: str, n: int | None = 3) -> None:
        """Read the columns of layout key `key` (`n` of them, or one when None)."""
        refs = self.lay[key]
        if n is None:
            refs = [refs]
        elif not isinstance(refs, (list, tuple)) or len(refs) != n:
            raise LogError(f'{self.table.source}: {self.stream}.{key}: expected a list of {n} columns, got {refs!r}')
        what = f'{self.stream}.{key}'
        self.cols[key] = np.stack([self.table.floats(r, what) for r in refs], axis=-1)

    def finish(self, allow_nan: dict[str, np.ndarray] | None = None) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """(t_ns of the kept rows, the columns of the kept rows); NaN rows counted. Sets
        `interval_ns` (kept rows): the time since the file's previous row, skipped or not
        (0: unknown, the first row or one after a row without a time)."""
        t = self.table.floats(self.lay['time'], f'{self.stream}.time')
        timed = np.isfinite(t)
        ok = timed.copy()
        for key, c in self.cols.items():
            fine = np.all(np.isfinite(c), axis=-1)
            if allow_nan and key in allow_nan:
                fine |= allow_nan[key]
            ok &= fine
        skipped = np.flatnonzero(~ok)
        self.report.skipped = len(skipped)
        self.report.skipped_lines = [int(self.table.lines[i]) for i in skipped[:LISTED]]
        if ok.sum() < 2:
            raise LogError(f'{self.table.source}: {self.stream}: {int(ok.sum())} usable rows of {len(ok)} '
                           f'(at least 2 needed)')
        t_all = self.table.times_ns(self.lay['time'], self.lay['time_unit'], f'{self.stream}.time', timed)
        idx = np.flatnonzero(timed)
        bad = np.flatnonzero(np.diff(t_all[idx]) <= 0)
        if len(bad):
            lines, ts = self.table.lines[idx], t_all[idx]
            where = '; '.join(f'{self.table.line_word} {lines[i + 1]} (t = {ts[i + 1] * 1e-9:.9g} s '
                              f'after {ts[i] * 1e-9:.9g} s at {lines[i]})' for i in bad[:LISTED])
            raise LogError(f'{self.table.source}: {self.stream}: time not increasing at {len(bad)} '
                           f'row(s): {where}')
        prev_timed = np.r_[False, timed[:-1]]
        self.interval_ns = np.where(prev_timed, t_all - np.r_[0, t_all[:-1]], 0)[ok]
        self.previous_kept = np.r_[False, ok[:-1]][ok]
        self.report.rows = int(ok.sum())
        return t_all[ok], {k: c[ok] for k, c in self.cols.items()}

    def unit(self, key: str, quantity: str) -> float:
        return factor(self.lay[key], quantity, f'{self.table.source}: {self.stream}.{key}')

    def where(self, key: str) -> str:
        return f'{self.table.source}: {self.stream}.{key}'

    def warn(self, text: str) -> None:
        self.report.warnings.append(text)


def _check_rate(r: _Reader, key: str, w: np.ndarray) -> None:
    p99 = float(np.percentile(np.linalg.norm(w, axis=1), 99))
    if p99 > MAX_RATE_RADPS:
        r.warn(f'{key}: rates up to {p99:.3g} rad/s (99th percentile) after conversion from '
               f'{r.lay[key + "_unit"]}: is the unit right (deg/s given as rad/s?)')


def _check_speed(r: _Reader, key: str, v: np.ndarray) -> None:
    p99 = float(np.percentile(np.linalg.norm(v, axis=1), 99))
    if p99 > MAX_SPEED_MPS:
        r.warn(f'{key}: speeds up to {p99:.3g} m/s (99th percentile) after conversion from '
               f'{r.lay[key + "_unit"]}: is the unit right?')


def read_imu(path: Path, lay: dict[str, Any]) -> ImuLog:
    r = _Reader('imu', path, lay)
    r.take('gyro')
    r.take('accel')
    t_ns, c = r.finish()
    inc = lay['kind'] == 'increments'
    a = conventions.body_to_flu(lay['body_axes'], r.where('body_axes'))
    gyro = c['gyro'] * r.unit('gyro_unit', 'angle' if inc else 'rate')
    accel = c['accel'] * r.unit('accel_unit', 'velocity' if inc else 'accel')
    if inc:     # a skipped row's increment is lost: its interval stays a gap in the stamps
        gyro = derive.rates_from_increments(t_ns, gyro, r.interval_ns)
        accel = derive.rates_from_increments(t_ns, accel, r.interval_ns)
    elif lay['rate_sampling'] == 'instant':
        gyro = derive.interval_means(gyro, r.previous_kept)
        accel = derive.interval_means(accel, r.previous_kept)
    elif lay['rate_sampling'] != 'mean':
        raise LogError(f"{r.where('rate_sampling')}: {lay['rate_sampling']!r}: expected mean (over the "
                       f"interval ending at the stamp) or instant (sampled at the stamp)")
    gyro, accel = gyro @ a.T, accel @ a.T
    _check_rate(r, 'gyro', gyro)
    spacing = derive.median_interval_ns(t_ns) * 1e-9
    if not IMU_SPACING_S[0] <= spacing <= IMU_SPACING_S[1]:
        r.warn(f'time: median spacing {spacing:.6g} s ({1 / spacing:.6g} Hz) after conversion from '
               f'{lay["time_unit"]}: is time_unit right (ms given as s?)')
    f_up = float(np.median(accel[:, 2]))
    if f_up < 0.0:
        r.warn(f'accel: median specific force along the body up axis {f_up:.4g} m/s^2: the axes point '
               f'down (FRD declared as {lay["body_axes"]}?)')
    f = float(np.median(np.linalg.norm(accel, axis=1)))
    if not SPECIFIC_FORCE_MPS2[0] <= f <= SPECIFIC_FORCE_MPS2[1]:
        r.warn(f'accel: median specific force {f:.4g} m/s^2 ({f / G0:.4g} g) after conversion from '
               f'{lay["accel_unit"]}; about 9.8 m/s^2 expected near the ground: is the unit right '
               f'(g given as m/s^2, m/s^2 as g{", a rate given as increments" if inc else ""}?)')
    return ImuLog(t_ns, gyro, accel, r.report)


def _attitude(r: _Reader, lay: dict[str, Any], c: dict[str, np.ndarray]) -> np.ndarray:
    if lay['attitude'] == 'quaternion':
        c_nb = conventions.quaternion_dcm(c['quaternion'], lay['quaternion_order'], lay['nav_frame'],
                                          lay['body_axes'], r.where('quaternion'), bool(lay['quaternion_inverse']))
        up = float(np.median(c_nb[:, 2, 2]))
        if up < 0.0:
            r.warn(f'quaternion: the body up axis points down (median up component {up:.3g}): are body_axes '
                   f'({lay["body_axes"]}), nav_frame ({lay["nav_frame"]}) and quaternion_inverse right?')
        return c_nb
    e = c['euler'] * r.unit('euler_unit', 'angle')
    if lay['euler_unit'] == 'rad' and float(np.max(np.abs(e))) > 2 * np.pi + 0.1:
        r.warn(f'euler: angles up to {float(np.max(np.abs(e))):.4g} rad: are they degrees (euler_unit: deg)?')
    if not isinstance(lay['yaw_negated'], bool):
        raise LogError(f"{r.where('yaw_negated')}: expected true or false, got {lay['yaw_negated']!r}")
    yaw = -e[:, 2] if lay['yaw_negated'] else e[:, 2]
    return conventions.euler_dcm(lay['attitude'], e[:, 0], e[:, 1], yaw, r.where('attitude'))


def read_master(path: Path, lay: dict[str, Any]) -> MasterLog:
    r = _Reader('master', path, lay)
    if lay['attitude'] == 'quaternion':
        r.take('quaternion', 4)
    else:
        r.take('euler')
    r.take('velocity')
    r.take('position')
    if lay['body_rate'] is not None:
        r.take('body_rate')
    t_ns, c = r.finish()
    c_nb = _attitude(r, lay, c)
    v = c['velocity'] * r.unit('velocity_unit', 'velocity')
    _check_speed(r, 'velocity', v)
    if lay['velocity_frame'] == 'nav':
        v_n = v @ conventions.nav_to_enu(lay['nav_frame'], r.where('nav_frame')).T
        v_b = derive.body_velocity(c_nb, v_n)
    elif lay['velocity_frame'] == 'body':
        v_b = v @ conventions.body_to_flu(lay['body_axes'], r.where('body_axes')).T
        v_n = np.einsum('nij,nj->ni', c_nb, v_b)
    else:
        raise LogError(f"{r.where('velocity_frame')}: {lay['velocity_frame']!r}: expected nav or body")
    ang = r.unit('position_unit', 'angle')
    lat, lon = c['position'][:, 0] * ang, c['position'][:, 1] * ang
    h = c['position'][:, 2] * r.unit('height_unit', 'length')
    if np.any(np.abs(lat) > np.pi / 2):
        raise LogError(f"{r.where('position')}: latitude beyond 90 deg after conversion from "
                       f"{lay['position_unit']} (degrees given as rad?)")
    if np.any(np.abs(lon) > 2 * np.pi):
        raise LogError(f"{r.where('position')}: longitude beyond 360 deg after conversion from "
                       f"{lay['position_unit']} (degrees given as rad?)")
    if lay['body_rate'] is not None:
        w_b = (c['body_rate'] * r.unit('body_rate_unit', 'rate')) @ conventions.body_to_flu(
            lay['body_axes'], r.where('body_axes')).T
        _check_rate(r, 'body_rate', w_b)
        if lay['body_rate_frame'] == 'ib':      # w_nb^b = w_ib^b - C_n^b (w_ie^n + w_en^n)
            w_b = w_b - derive.body_velocity(c_nb, earth.omega_ie_n(lat) + earth.omega_en_n(lat, h, v_n))
        elif lay['body_rate_frame'] != 'nb':
            raise LogError(f"{r.where('body_rate_frame')}: {lay['body_rate_frame']!r}: expected nb (w.r.t. "
                           f"the local-level frame) or ib (w.r.t. inertial space)")
    else:
        w_b = derive.body_rate_from_attitude(t_ns, c_nb)
    return MasterLog(t_ns, conventions.dcm_to_quat(c_nb), v_b, w_b, lat, lon, h,
                     lay['body_rate'] is None, r.report)


def read_velocity(stream: str, path: Path, lay: dict[str, Any]) -> VelocityLog:
    """The LDV (ship axes) or Doppler radar (aircraft axes) stream."""
    r = _Reader(stream, path, lay)
    r.take('velocity')
    if lay['sigma'] is not None:
        r.take('sigma', None)
        missing = r.cols['sigma'][:, 0] < 0.0
        t_ns, c = r.finish({'velocity': missing})
        sigma = c['sigma'][:, 0]
        sigma = np.where(sigma < 0.0, -1.0, sigma * r.unit('sigma_unit', 'velocity'))
    else:                               # one sigma, m/s, for every row
        t_ns, c = r.finish()
        sigma = np.full(len(t_ns), float(lay['sigma_mps']))
    valid = sigma >= 0.0
    v = c['velocity'] * r.unit('velocity_unit', 'velocity')
    v = np.where(valid[:, None], v @ conventions.body_to_flu(lay['body_axes'], r.where('body_axes')).T, 0.0)
    if valid.any():
        _check_speed(r, 'velocity', v[valid])
    return VelocityLog(t_ns, v, np.where(valid, sigma, np.nan), valid, r.report)
