"""Scenario files: one validated configuration drives both the node graph and the batch
pipeline. Unknown keys, wrong types and out-of-range values fail with the dotted key named.
"""
from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from alignment_core.aircraft.catapult import track_length_from_dict
from alignment_core.aircraft.kinematics import AircraftConfig, check_catapult_grid
from alignment_core.estimation.config import FilterConfig
from alignment_core.sensors import presets as sensor_presets
from alignment_core.sensors.doppler_radar import DopplerConfig
from alignment_core.sensors.imu import ImuConfig
from alignment_core.sensors.ldv import LdvConfig
from alignment_core.sensors.master_ins import MasterConfig
from alignment_core.sensors.timing import check_rate
from alignment_core.ship.config import ShipConfig
from alignment_core.validation import ConfigError, build, require, to_dict


@dataclass(frozen=True)
class Scenario:
    """A complete run: timing, seed and every stage's configuration."""
    name: str = 'catapult'
    description: str = ''
    seed: int = 1
    duration_s: float = 68.0
    rate_hz: float = 100.0
    start_time_s: float = 1.0
    ship: ShipConfig = field(default_factory=ShipConfig)
    master: MasterConfig = field(default_factory=MasterConfig)
    aircraft: AircraftConfig = field(default_factory=AircraftConfig)
    imu: ImuConfig = field(default_factory=ImuConfig)
    ldv: LdvConfig = field(default_factory=LdvConfig)
    doppler: DopplerConfig = field(default_factory=DopplerConfig)
    filter: FilterConfig = field(default_factory=FilterConfig)

    def validate(self) -> None:
        require(0 <= self.seed < 2**63, f"seed must be a non-negative integer, got {self.seed}")
        require(0.0 < self.duration_s <= 86400.0, f"duration_s must be in (0, 86400], got {self.duration_s}")
        require(1.0 <= self.rate_hz <= 2000.0, f"rate_hz must be in [1, 2000], got {self.rate_hz}")
        require(abs(1e9 / self.rate_hz - round(1e9 / self.rate_hz)) < 1e-6,
                f"rate_hz = {self.rate_hz} must give an integer number of nanoseconds per sample")
        require(self.start_time_s > 0.0, f"start_time_s must be > 0 (0 means 'no clock' in ROS), "
                                         f"got {self.start_time_s}")
        require(abs(self.duration_s * self.rate_hz - round(self.duration_s * self.rate_hz)) < 1e-6,
                "duration_s must be a whole number of samples")
        if self.aircraft.catapult.enabled:
            check_catapult_grid(self.aircraft.catapult, self.rate_hz)
        check_rate('master.rate_hz', self.master.rate_hz, self.rate_hz)
        check_rate('ldv.rate_hz', self.ldv.rate_hz, self.rate_hz)
        if self.doppler.enabled:
            check_rate('doppler.rate_hz', self.doppler.rate_hz, self.rate_hz)
        require(self.doppler.enabled or self.filter.model != 'seed001_13',
                "filter.model seed001_13 matches the Doppler radar: set doppler.enabled true")

    @property
    def dt_ns(self) -> int:
        return int(round(1e9 / self.rate_hz))

    @property
    def t0_ns(self) -> int:
        return int(round(self.start_time_s * 1e9))

    @property
    def n_samples(self) -> int:
        """Ship samples k = 0 .. n_samples - 1 (both ends of the run included)."""
        return int(round(self.duration_s * self.rate_hz)) + 1


def tau_of(t_ns: int, t0_ns: int) -> float:
    """Seconds since the scenario start, computed identically everywhere from stamps."""
    return (t_ns - t0_ns) / 1e9


def config_dir() -> Path:
    root = os.environ.get('ALIGN_ROOT')
    if root:
        return Path(root) / 'config'
    return Path(__file__).resolve().parents[3] / 'config'


def scenario_path(name_or_path: str) -> Path:
    p = Path(name_or_path)
    if p.suffix in ('.yaml', '.yml') and p.exists():
        return p
    cand = config_dir() / 'scenarios' / f'{name_or_path}.yaml'
    if cand.exists():
        return cand
    avail = sorted(x.stem for x in (config_dir() / 'scenarios').glob('*.yaml'))
    raise ConfigError(f"unknown scenario {name_or_path!r} (available: {', '.join(avail)})")


def _set_dotted(d: dict, key: str, value) -> None:
    parts = key.split('.')
    cur = d
    for p in parts[:-1]:
        nxt = cur.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise ConfigError(f"--set {key}: {p} is not a section")
        cur = nxt
    cur[parts[-1]] = value


def parse_overrides(items: list[str] | tuple[str, ...]) -> dict[str, object]:
    """['ship.sea_state=6', ...] -> {'ship.sea_state': 6}; values parsed as YAML scalars."""
    out = {}
    for it in items:
        if '=' not in it:
            raise ConfigError(f"--set expects KEY=VALUE, got {it!r}")
        k, v = it.split('=', 1)
        out[k.strip()] = yaml.safe_load(v)
    return out


def from_dict(data: dict, overrides: dict[str, object] | None = None) -> Scenario:
    data = copy.deepcopy(data) if data else {}
    for k, v in (overrides or {}).items():
        _set_dotted(data, k, v)
    sensor_presets.apply(data)           # imu.preset / master.preset fill the keys not given
    # the filter and the LDV know the surveyed deck spot unless told otherwise; the LDV
    # beam covers the catapult track (hold-back creep + stroke length + 0.5 m), so matching ends at the release
    ac = data.get('aircraft') or {}
    if 'lever_arm_m' in ac:
        data.setdefault('filter', {})
        if data['filter'] is None:
            data['filter'] = {}
        data['filter'].setdefault('lever_arm_m', ac['lever_arm_m'])
        data.setdefault('ldv', {})
        if data['ldv'] is None:
            data['ldv'] = {}
        data['ldv'].setdefault('origin_m', ac['lever_arm_m'])
    if 'heading_on_deck_deg' in ac:      # the nominal mounting on deck, and the LDV beam along the track
        for sec, key in (('filter', 'heading_on_deck_deg'), ('ldv', 'track_heading_deg')):
            if data.get(sec) is None:
                data[sec] = {}
            data[sec].setdefault(key, ac['heading_on_deck_deg'])
    cat = ac.get('catapult') or {}
    if cat.get('enabled', True):
        data.setdefault('ldv', {})
        if data['ldv'] is None:
            data['ldv'] = {}
        data['ldv'].setdefault('track_length_m', track_length_from_dict(cat) + 0.5)
    return build(Scenario, data)


def load(name_or_path: str, overrides: dict[str, object] | None = None,
         seed: int | None = None) -> Scenario:
    """Load a scenario by name (config/scenarios/NAME.yaml) or path, apply dotted overrides."""
    path = scenario_path(name_or_path)
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a scenario must be a mapping")
    ov = dict(overrides or {})
    if seed is not None:
        ov['seed'] = seed
    return from_dict(data, ov)


def dump(sc: Scenario) -> str:
    return yaml.safe_dump(to_dict(sc), sort_keys=False)


def build_scenario(data: dict) -> Scenario:
    """Validate a complete nested dict (no defaulting of the filter's lever arm)."""
    return build(Scenario, data)
