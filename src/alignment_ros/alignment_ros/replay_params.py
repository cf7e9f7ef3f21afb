"""The filter's parameters for a replay: a params file (the run's params.yaml next to the bag,
or --params-file), --set overrides, and what the data says where neither gives it.

The world origin (ship.lat_deg, ship.lon_deg) and the IMU rate (rate_hz) are taken, in this
order, from: --set; the params file's own entries; the importer's record in the bag's
metadata (the origin its positions are relative to, the IMU's median stamp spacing); the
params file's scenario defaults (a params file of a run of the graph defines its whole
scenario); the data (the first /master/fix, the /aircraft/imu stamp spacing). For an imported
bag a params file's rate or origin that contradicts the importer's is refused (only --set
overrides those).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from rclpy.serialization import deserialize_message

from alignment_core.config import scenario as core_scenario
from alignment_core.config.given import flatten
from alignment_core.recorded.derive import rate_hz_of

from . import importer, topics
from .bag import BagReader
from .params import NODE_SCOPES, node_scenario, params_file_given
from .topics import msg_class

FILTER = 'alignment_filter_node'
ORIGIN_KEYS = ('ship.lat_deg', 'ship.lon_deg')
ORIGIN_AGREES_DEG = 1e-9
RATE_AGREES = 1e-9           # relative


def _first_fix(reader: BagReader) -> tuple[float, float] | None:
    for m in reader.messages([topics.MASTER_FIX]):
        fix = deserialize_message(m.data, msg_class(m.type_name))
        return float(fix.latitude), float(fix.longitude)
    return None


def _imu_rate(reader: BagReader) -> float:
    t = np.array([m.t_ns for m in reader.messages([topics.AIRCRAFT_IMU])], dtype=np.int64)
    if len(t) < 2:
        raise ValueError(f'{reader.path}: fewer than two {topics.AIRCRAFT_IMU} messages')
    return rate_hz_of(t)


def _check_file_against_import(meta: dict[str, str], file_given: dict[str, Any], overrides: dict[str, Any],
                               params_file: Path | None) -> None:
    """ValueError when the params file gives an IMU rate or an origin that contradicts the
    importer's (the rate drives gap detection, bridging, filtering and noise discretisation; the
    bag's positions are relative to that origin); --set may still override them knowingly."""
    rate = float(meta[importer.IMU_RATE])
    if 'rate_hz' in file_given and 'rate_hz' not in overrides and \
            abs(float(file_given['rate_hz']) - rate) > RATE_AGREES * rate:
        raise ValueError(f'{params_file} gives rate_hz {file_given["rate_hz"]} but the imported IMU log runs at '
                         f'{rate:.6g} Hz ({importer.IMU_RATE} in the bag metadata): remove rate_hz from the '
                         f'params file, or --set rate_hz=... to override')
    origin = (float(meta[importer.ORIGIN_LAT]), float(meta[importer.ORIGIN_LON]))
    for key, value in zip(ORIGIN_KEYS, origin):
        if key in file_given and key not in overrides and abs(float(file_given[key]) - value) > ORIGIN_AGREES_DEG:
            raise ValueError(f'{params_file} gives {key} {file_given[key]} but the imported bag\'s positions are '
                             f'relative to the origin {origin[0]:.9f}, {origin[1]:.9f} deg (bag metadata): remove '
                             f'{", ".join(ORIGIN_KEYS)} from the params file, or --set them to override')


def replay_parameters(bag: Path, params_file: Path | None, sets: list[str]
                      ) -> tuple[dict[str, Any], list[str]]:
    """(the filter's parameters, flat; one line per value taken from the data). ConfigError
    for a bad --set or an invalid result, ValueError when the data cannot give what is needed."""
    file_given = flatten(params_file_given(params_file, FILTER)) if params_file is not None else {}
    overrides = flatten(core_scenario.parse_overrides(sets))
    given = {**file_given, **overrides}
    reader = BagReader(bag)
    meta = reader.metadata().custom_data or {}
    notes: list[str] = []
    imported = importer.ORIGIN_LAT in meta
    if imported:
        _check_file_against_import(meta, file_given, overrides, params_file)
    if imported and all(k in given for k in ORIGIN_KEYS):
        lat, lon = float(meta[importer.ORIGIN_LAT]), float(meta[importer.ORIGIN_LON])
        if max(abs(given['ship.lat_deg'] - lat), abs(given['ship.lon_deg'] - lon)) > ORIGIN_AGREES_DEG:
            notes.append(f'the bag\'s positions are relative to the origin {lat:.9f}, {lon:.9f} deg; '
                         f'the filter is given {given["ship.lat_deg"]}, {given["ship.lon_deg"]}')
    if not all(k in given for k in ORIGIN_KEYS):
        if imported:
            lat, lon = float(meta[importer.ORIGIN_LAT]), float(meta[importer.ORIGIN_LON])
            notes.append(f'origin {lat:.9f}, {lon:.9f} deg: the importer\'s (bag metadata)')
        elif params_file is None:
            fix = _first_fix(reader)
            if fix is None:
                raise ValueError(f'{bag}: no {topics.MASTER_FIX} to take the origin from: '
                                 '--set ship.lat_deg=... --set ship.lon_deg=...')
            lat, lon = fix
            notes.append(f'origin {lat:.9f}, {lon:.9f} deg: the first {topics.MASTER_FIX}')
        if imported or params_file is None:
            given.setdefault('ship.lat_deg', lat)
            given.setdefault('ship.lon_deg', lon)
    if 'rate_hz' not in given:
        if imported:
            given['rate_hz'] = float(meta[importer.IMU_RATE])
            notes.append(f'IMU rate {given["rate_hz"]:.6g} Hz: the importer\'s (bag metadata)')
        elif params_file is None:
            given['rate_hz'] = _imu_rate(reader)
            notes.append(f'IMU rate {given["rate_hz"]:.6g} Hz: the {topics.AIRCRAFT_IMU} stamp spacing')
    if not all(math.isfinite(v) for k, v in given.items() if k in (*ORIGIN_KEYS, 'rate_hz')):
        raise ValueError('the origin and the IMU rate must be finite')
    node_scenario(given, NODE_SCOPES[FILTER])         # ConfigError now, not in the node
    return given, notes


def write_params(given: dict[str, Any], path: Path) -> None:
    """A params file giving every node (here: the filter) the flat parameters `given`."""
    path.write_text(yaml.safe_dump({'/**': {'ros__parameters': given}}, sort_keys=False))
