"""The layout of a log: where each quantity is (columns by name or 0-based index), in which
unit, axes and convention. The canonical layout (CANONICAL) is the default; a map (a small
YAML file, read into a dict) replaces any of its keys, per stream.

Keys per stream (every stream: `time`, `time_unit`, and the file's `header`, `delimiter`,
`variable` and `names` for a .mat matrix):
- imu: `kind` (increments | rates), `rate_sampling` (rates: mean over the interval ending at
  the stamp, or instant: sampled at the stamp), `body_axes`, `gyro`, `gyro_unit`, `accel`, `accel_unit`;
- master: `body_axes`, `nav_frame` (an Euler convention sets both), `attitude` (quaternion |
  an Euler convention),
  `quaternion`, `quaternion_order`, `quaternion_inverse`, `euler` (roll, pitch, yaw columns),
  `euler_unit`, `yaw_negated` (the log's yaw is the convention's negated: a clockwise heading
  in an enu_rfu_312 log), `velocity`, `velocity_frame` (nav | body), `velocity_unit`, `position`
  (latitude, longitude, height), `position_unit` (of latitude and longitude), `height_unit`,
  `body_rate` (optional; derived from the attitude without it), `body_rate_unit`,
  `body_rate_frame` (nb: w_nb^b, w.r.t. the local-level frame, as /master/odom carries it;
  ib: w_ib^b, an INS's gyro-frame rate, from which C_n^b (w_ie^n + w_en^n) is subtracted);
- ldv (ship axes) and doppler (aircraft axes): `body_axes`, `velocity`, `velocity_unit`,
  `sigma` (a column by name or 0-based index; a negative sigma: no measurement in that row),
  `sigma_unit`, or `sigma_mps` (one sigma, m/s, for every row).
Top level: `time_offset_s` (`auto`: shift the times so that they start at 1 s when they
start at or below 0, else keep them; or a number of seconds added to every stamp).
"""
from __future__ import annotations

import copy
from typing import Any

from .column_units import LogError
from .conventions import EULER_FRAMES

STREAMS = ('imu', 'master', 'ldv', 'doppler')
FILE_KEYS = ('header', 'delimiter', 'variable', 'names', 'time', 'time_unit')

CANONICAL: dict[str, dict[str, Any]] = {
    'imu': {'time': 't_s', 'kind': 'increments', 'body_axes': 'FLU',
            'gyro': ['dtheta_x_rad', 'dtheta_y_rad', 'dtheta_z_rad'],
            'accel': ['dv_x_mps', 'dv_y_mps', 'dv_z_mps']},
    'master': {'time': 't_s', 'body_axes': 'FLU', 'nav_frame': 'ENU', 'attitude': 'quaternion',
               'quaternion': ['qw', 'qx', 'qy', 'qz'], 'quaternion_order': 'wxyz',
               'velocity': ['v_e_mps', 'v_n_mps', 'v_u_mps'], 'velocity_frame': 'nav',
               'position': ['lat_deg', 'lon_deg', 'h_m'], 'position_unit': 'deg'},
    'ldv': {'time': 't_s', 'body_axes': 'FLU', 'velocity': ['v_x_mps', 'v_y_mps', 'v_z_mps'],
            'sigma': 'sigma_mps'},
    'doppler': {'time': 't_s', 'body_axes': 'FLU', 'velocity': ['v_x_mps', 'v_y_mps', 'v_z_mps'],
                'sigma': 'sigma_mps'},
}
"""The canonical CSV layout (header row required): body FLU, nav ENU, SI units, increments."""

DEFAULTS: dict[str, dict[str, Any]] = {
    'imu': {'time_unit': 's', 'header': True, 'delimiter': None, 'variable': None, 'names': None,
            'gyro_unit': None, 'accel_unit': None, 'rate_sampling': 'mean'},
    'master': {'time_unit': 's', 'header': True, 'delimiter': None, 'variable': None, 'names': None,
               'quaternion_inverse': False, 'euler': None, 'euler_unit': 'rad', 'yaw_negated': False,
               'velocity_unit': 'm/s', 'height_unit': 'm', 'body_rate': None, 'body_rate_unit': 'rad/s',
               'body_rate_frame': 'nb'},
    'ldv': {'time_unit': 's', 'header': True, 'delimiter': None, 'variable': None, 'names': None,
            'velocity_unit': 'm/s', 'sigma_unit': 'm/s', 'sigma_mps': None},
    'doppler': {'time_unit': 's', 'header': True, 'delimiter': None, 'variable': None, 'names': None,
                'velocity_unit': 'm/s', 'sigma_unit': 'm/s', 'sigma_mps': None},
}
"""Keys the canonical layout leaves implicit (units of increments follow `kind`)."""


def stream_layout(stream: str, given: dict[str, Any] | None) -> dict[str, Any]:
    """The full layout of `stream`: the canonical one with the map's keys replacing its own;
    LogError naming an unknown key."""
    out = {**DEFAULTS[stream], **copy.deepcopy(CANONICAL[stream])}
    given = given or {}
    if not isinstance(given, dict):
        raise LogError(f'map: {stream}: expected a mapping of keys, got {given!r}')
    unknown = sorted(set(given) - set(out))
    if unknown:
        raise LogError(f'map: {stream}: unknown key(s) {", ".join(unknown)} (known: {", ".join(sorted(out))})')
    out.update(given)
    if stream == 'imu':
        inc = out['kind'] == 'increments'
        if out['kind'] not in ('increments', 'rates'):
            raise LogError(f"map: imu.kind: {out['kind']!r}: expected increments or rates")
        out['gyro_unit'] = out['gyro_unit'] or ('rad' if inc else 'rad/s')
        out['accel_unit'] = out['accel_unit'] or ('m/s' if inc else 'm/s^2')
    if stream == 'master' and out['attitude'] != 'quaternion':
        _euler_frames(out, given)
    if stream in ('ldv', 'doppler'):
        _sigma(stream, out, given)
    return out


def _sigma(stream: str, out: dict[str, Any], given: dict[str, Any]) -> None:
    """`sigma` is a column (name or 0-based index); `sigma_mps` one sigma (m/s) for every row."""
    if isinstance(given.get('sigma'), float):
        raise LogError(f"map: {stream}.sigma: {given['sigma']!r}: a column (name or 0-based index); one sigma "
                       f"for every row is `sigma_mps: {given['sigma']!r}`")
    if given.get('sigma_mps') is None:
        return
    s = given['sigma_mps']
    if 'sigma' in given:
        raise LogError(f'map: {stream}: sigma (a column) and sigma_mps (one for every row) both given')
    if isinstance(s, bool) or not isinstance(s, (int, float)) or not s > 0.0:
        raise LogError(f'map: {stream}.sigma_mps: expected a positive number of m/s, got {s!r}')
    out['sigma'] = None


def _euler_frames(out: dict[str, Any], given: dict[str, Any]) -> None:
    """An Euler convention fixes the master's frames: nav_frame and body_axes (of the velocity,
    the body rate) default to its own; LogError when the map gives others."""
    att = out['attitude']
    if att not in EULER_FRAMES:
        raise LogError(f'map: master.attitude: {att!r}: expected quaternion or one of {", ".join(EULER_FRAMES)}')
    if 'euler' not in given:
        raise LogError(f"map: master: attitude {att!r} needs `euler: [roll, pitch, yaw]` columns")
    for key, own in zip(('nav_frame', 'body_axes'), EULER_FRAMES[att]):
        if key in given and given[key] != own:
            raise LogError(f'map: master.{key}: {given[key]!r} contradicts attitude {att!r}, whose {key} '
                           f'is {own} (leave {key} out: the convention sets it)')
        out[key] = own


def read_map(doc: dict[str, Any] | None) -> tuple[dict[str, dict[str, Any]], str | float]:
    """(layout of every stream, time offset: 'auto' or seconds) from a map's contents."""
    doc = dict(doc or {})
    offset = doc.pop('time_offset_s', 'auto')
    if offset != 'auto' and (isinstance(offset, bool) or not isinstance(offset, (int, float))):
        raise LogError(f'map: time_offset_s: expected auto or a number of seconds, got {offset!r}')
    unknown = sorted(set(doc) - set(STREAMS))
    if unknown:
        raise LogError(f'map: unknown section(s) {", ".join(unknown)} (known: {", ".join(STREAMS)}, time_offset_s)')
    return {s: stream_layout(s, doc.get(s)) for s in STREAMS}, offset
