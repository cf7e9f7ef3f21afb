"""What a user gave, before it becomes a Scenario: a nested mapping (a scenario file, --set
overrides, a node's parameters), the rules that derive the keys not given from the keys given,
and the scopes of keys a reader (a node) takes. `scenario.resolve` applies them for the command
line and for the nodes alike, so both give the same scenario from the same keys.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from alignment_core.aircraft.catapult import track_length_from_dict
from alignment_core.estimation import presets as filter_presets
from alignment_core.rng import stage_rng
from alignment_core.sensors import presets as sensor_presets
from alignment_core.validation import ConfigError

LDV_TRACK_MARGIN_M = 0.5
"""The LDV beam covers the catapult track (hold-back creep + stroke length) plus this, so
matching ends at the release."""


@dataclass(frozen=True)
class Scope:
    """The scenario keys one reader takes: whole sections ('ship', 'aircraft.catapult') or
    single keys ('ship.lat_deg')."""
    keys: tuple[str, ...]

    def covers(self, key: str) -> bool:
        """`key` (a dotted key or a section) lies in the scope."""
        return any(key == k or key.startswith(k + '.') for k in self.keys)

    def __str__(self) -> str:
        return ', '.join(self.keys)


def flatten(data: dict | None, prefix: str = '') -> dict[str, Any]:
    """Nested mapping -> {'dotted.key': value}."""
    out: dict[str, Any] = {}
    for k, v in (data or {}).items():
        if isinstance(v, dict):
            out.update(flatten(v, f'{prefix}{k}.'))
        else:
            out[f'{prefix}{k}'] = v
    return out


def nest(flat: dict[str, Any]) -> dict:
    """{'dotted.key': value} -> nested mapping (lists for tuples)."""
    out: dict = {}
    for key, value in flat.items():
        set_dotted(out, key, list(value) if isinstance(value, (list, tuple)) else value)
    return out


def set_dotted(data: dict, key: str, value: Any) -> None:
    parts = key.split('.')
    cur = data
    for p in parts[:-1]:
        if cur.get(p) is None:          # a section given empty (`filter:` in YAML)
            cur[p] = {}
        cur = cur[p]
        if not isinstance(cur, dict):
            raise ConfigError(f"{key}: {p} is not a section")
    cur[parts[-1]] = value


def with_overrides(data: dict | None, overrides: dict[str, Any] | None) -> dict:
    """A copy of `data` with the dotted `overrides` set (the later key wins)."""
    out = copy.deepcopy(data) if data else {}
    for key, value in (overrides or {}).items():
        set_dotted(out, key, value)
    return out


FOLLOWS = {
    'filter.lever_arm_m': 'aircraft.lever_arm_m',                   # the surveyed deck spot
    'ldv.origin_m': 'aircraft.lever_arm_m',
    'filter.heading_on_deck_deg': 'aircraft.heading_on_deck_deg',   # the nominal mounting on deck
    'ldv.track_heading_deg': 'aircraft.heading_on_deck_deg',        # the beam along the track
    'ldv.track_length_m': 'aircraft.catapult',       # hold-back creep + stroke + LDV_TRACK_MARGIN_M
    'filter.ldv_mode': 'ldv.mode',                   # the LDV installed: vector or beam
}
"""Key not given -> the given key (or section) its value follows (see `fill_defaults`)."""

SURVEY_SIGMA_KEY = 'aircraft.lever_arm_survey_sigma_m'
DEFAULT_LEVER_ARM_M = (40.0, -10.0, 15.0)
"""AircraftConfig's and FilterConfig's default lever arm (the survey error applies to it when
aircraft.lever_arm_m is not given)."""


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def surveyed_lever_arm(data: dict, default_seed: int) -> list[float] | None:
    """The filter's lever arm when filter.lever_arm_m is not given and the survey error is on:
    aircraft.lever_arm_m (the true spot) plus a random constant per axis of 1-sigma
    aircraft.lever_arm_survey_sigma_m, drawn once per seed (stream 'lever_arm_survey'). None when
    the error is off (0, the default) or a value is malformed (validation then names it)."""
    sigma = _lookup(data, SURVEY_SIGMA_KEY)[1]
    if not _number(sigma) or sigma <= 0.0:
        return None
    found, arm = _lookup(data, 'aircraft.lever_arm_m')
    arm = arm if found else DEFAULT_LEVER_ARM_M
    seed = data.get('seed', default_seed)
    if not (isinstance(arm, (list, tuple)) and len(arm) == 3 and all(_number(a) for a in arm)
            and isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        return None
    err = stage_rng(seed, 'lever_arm_survey').standard_normal(3) * float(sigma)
    return [float(a) + float(e) for a, e in zip(arm, err)]


def _lookup(data: dict, key: str) -> tuple[bool, Any]:
    cur: Any = data
    for p in key.split('.'):
        if not isinstance(cur, dict) or p not in cur:
            return False, None
        cur = cur[p]
    return True, cur


def fill_defaults(data: dict, default_seed: int = 1) -> dict:
    """Fill, in place, the keys the given ones imply (an explicit key always wins): each
    sensor preset (imu.preset, master.preset) and the filter preset (filter.preset) its
    section's keys, then the keys of FOLLOWS from theirs; ldv.track_length_m follows the
    catapult whenever it is enabled (its default);
    filter.lever_arm_m is the surveyed spot, off the true one by the survey error when
    aircraft.lever_arm_survey_sigma_m > 0 (`surveyed_lever_arm`; default_seed: the scenario's
    seed when none is given). Returns data."""
    sensor_presets.apply(data)
    filter_presets.apply(data)
    for key, source in FOLLOWS.items():
        if _lookup(data, key)[0]:
            continue
        if key == 'filter.lever_arm_m':
            surveyed = surveyed_lever_arm(data, default_seed)
            if surveyed is not None:
                set_dotted(data, key, surveyed)
                continue
        if key == 'ldv.track_length_m':
            cat = _lookup(data, source)[1] or {}
            if isinstance(cat, dict) and cat.get('enabled', True):
                set_dotted(data, key, track_length_from_dict(cat) + LDV_TRACK_MARGIN_M)
            continue
        found, value = _lookup(data, source)
        if found:
            set_dotted(data, key, value)
    return data


def within(data: dict, scope: Scope) -> dict:
    """The part of nested `data` whose keys lie in `scope`."""
    return nest({k: v for k, v in flatten(data).items() if scope.covers(k)})
