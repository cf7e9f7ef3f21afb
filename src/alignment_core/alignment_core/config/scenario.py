"""Scenario files: one validated configuration drives both the node graph and the batch
pipeline. Unknown keys, wrong types and out-of-range values fail with the dotted key named.

`resolve` is the one way from what a user gave (a scenario file with --set overrides, or a
node's parameters) to a Scenario: overrides, presets and defaulting rules (config/given.py),
then validation; a node passes its scope and gets the checks its keys allow.
"""
from __future__ import annotations

import dataclasses
import os
import typing
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from alignment_core.aircraft.aircraft_config import AircraftConfig
from alignment_core.aircraft.catapult import check_catapult_grid
from alignment_core.config.given import Scope, fill_defaults, with_overrides, within
from alignment_core.estimation.air_data.config import AirDataFilterConfig
from alignment_core.estimation.config import FilterConfig
from alignment_core.sensors.doppler_radar import DopplerConfig
from alignment_core.sensors.fads_config import FadsConfig
from alignment_core.sensors.imu import ImuConfig
from alignment_core.sensors.ldv import LdvConfig
from alignment_core.sensors.master_ins import MasterConfig
from alignment_core.sensors.reference_ins import ReferenceInsConfig
from alignment_core.sensors.timing import check_rate, decimation
from alignment_core.ship.config import ShipConfig
from alignment_core.validation import ConfigError, build, require, to_dict

MAX_END_S = 2e9
"""start_time_s + duration_s at most: stamps are int64 ns (up to 9.2e9 s) and a ROS header's seconds
int32 (up to 2^31 s = 2.147e9 s, 2038 as Unix time); the margin holds the run-out and latencies."""


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
    fads: FadsConfig = field(default_factory=FadsConfig)
    reference_ins: ReferenceInsConfig = field(default_factory=ReferenceInsConfig)
    air_data_filter: AirDataFilterConfig = field(default_factory=AirDataFilterConfig)

    def validate(self, covers: Callable[[str], bool] = lambda key: True) -> None:
        """Ranges and consistency. `covers` (a node's scope) limits the checks to those whose
        keys it takes; the others are for the nodes that take their keys."""
        def given(*keys: str) -> bool:
            return all(covers(k) for k in keys)
        if given('seed'):
            require(0 <= self.seed < 2**63, f"seed must be a non-negative integer, got {self.seed}")
        if given('duration_s'):
            require(0.0 < self.duration_s <= 86400.0, f"duration_s must be in (0, 86400], got {self.duration_s}")
        if given('rate_hz'):
            require(1.0 <= self.rate_hz <= 2000.0, f"rate_hz must be in [1, 2000], got {self.rate_hz}")
            require(abs(1e9 / self.rate_hz - round(1e9 / self.rate_hz)) < 1e-6,
                    f"rate_hz = {self.rate_hz} must give an integer number of nanoseconds per sample")
        if given('start_time_s'):
            require(self.start_time_s > 0.0, f"start_time_s must be > 0 (0 means 'no clock' in ROS), "
                                             f"got {self.start_time_s}")
            duration = self.duration_s if given('duration_s') else 0.0
            require(self.start_time_s + duration <= MAX_END_S,
                    f"start_time_s + duration_s must be <= {MAX_END_S:g} s (stamps in int64 ns and a ROS header's "
                    f"int32 seconds, up to 2^31 s), got {self.start_time_s:g} + {duration:g} s")
        if given('duration_s', 'rate_hz'):
            require(abs(self.duration_s * self.rate_hz - round(self.duration_s * self.rate_hz)) < 1e-6,
                    "duration_s must be a whole number of samples")
        if self.aircraft.catapult.enabled and given('aircraft.catapult', 'rate_hz'):
            check_catapult_grid(self.aircraft.catapult, self.rate_hz)
        if given('master.rate_hz', 'rate_hz'):
            check_rate('master.rate_hz', self.master.rate_hz, self.rate_hz)
        if self.master.latency_jitter_s > 0.0 and given('master.rate_hz', 'rate_hz', 'master.latency_jitter_s'):
            interval = 1.0 / (self.master.rate_hz if self.master.rate_hz > 0.0 else self.rate_hz)
            require(self.master.latency_jitter_s < interval,
                    f"master.latency_jitter_s = {self.master.latency_jitter_s} s must be below the master's sample "
                    f"interval {interval} s (its stamps must stay in order)")
        if given('ldv.rate_hz', 'rate_hz'):
            check_rate('ldv.rate_hz', self.ldv.rate_hz, self.rate_hz)
        if self.doppler.enabled and given('doppler.rate_hz', 'rate_hz'):
            check_rate('doppler.rate_hz', self.doppler.rate_hz, self.rate_hz)
        if given('doppler.enabled', 'filter.model'):
            require(self.doppler.enabled or self.filter.model != 'seed001_13',
                    "filter.model seed001_13 matches the Doppler radar: set doppler.enabled true")
        if given('master', 'ship.lat_deg'):
            self.master.validate_at(self.ship.lat_deg)
        self.validate_filter_fit(given)

    def validate_filter_fit(self, given: Callable[..., bool]) -> None:
        """The filter's options against the sensors and the aircraft it is given (FilterConfig alone
        stays permissive: it also runs on recorded data)."""
        f = self.filter
        if given('ldv.mode', 'filter.ldv_mode'):
            require(f.ldv_mode == self.ldv.mode,
                    f"filter.ldv_mode = {f.ldv_mode} contradicts ldv.mode = {self.ldv.mode}: the filter would reject "
                    f"every LDV sample as of the wrong kind (leave filter.ldv_mode out: it follows ldv.mode; "
                    f"for a beam LDV set ldv.mode: beam)")
        if f.relative_velocity == 'zero' and given('filter.relative_velocity', 'aircraft', 'duration_s'):
            moving = self.moves_on_deck()
            require(not moving, f"filter.relative_velocity zero takes the slave as rigidly tied to the master's "
                                f"body, but {moving}: use auto or ldv")
        every = decimation(self.master.rate_hz, self.rate_hz)
        if f.rate_matching and given('filter', 'master', 'rate_hz'):
            why = ("its rate rows need the master valid (at its stamp - filter.master_latency_s) at the end of an IMU "
                   "interval and its previous sample one IMU interval earlier; else none is formed (rate_unmatched)")
            require(every == 1, f"filter.rate_matching needs the master at the IMU rate: master.rate_hz = "
                                f"{self.master.rate_hz:g} Hz is not rate_hz = {self.rate_hz:g} Hz ({why})")
            require(self.master.latency_jitter_s == 0.0,
                    f"filter.rate_matching needs master stamps on the IMU grid: master.latency_jitter_s = "
                    f"{self.master.latency_jitter_s:g} s moves them off it ({why})")
            offset_ns = round(self.master.latency_s * 1e9) - round(f.master_latency_s * 1e9)
            require(offset_ns % self.dt_ns == 0,
                    f"filter.rate_matching needs the master's validity times on the IMU grid: master.latency_s = "
                    f"{self.master.latency_s:g} s less filter.master_latency_s = {f.master_latency_s:g} s is "
                    f"{offset_ns} ns, not a multiple of the IMU interval {self.dt_ns} ns ({why})")
        if f.lever_arm_treatment == 'butterworth' and given('filter', 'master.rate_hz', 'rate_hz'):
            require(every == 1,
                    f"filter.lever_arm_treatment butterworth: its low-pass is designed at the IMU rate (rate_hz = "
                    f"{self.rate_hz:g} Hz) but stepped once per master match, so master.rate_hz = "
                    f"{self.master.rate_hz:g} Hz would move its cutoff from {f.butterworth_cutoff_hz:g} Hz to "
                    f"{f.butterworth_cutoff_hz / every:g} Hz: give master.rate_hz 0 (the scenario rate) or use "
                    f"compensation")

    def moves_on_deck(self) -> str:
        """Why the aircraft moves relative to the deck during the run ('' if it does not): an
        airborne start, or a catapult launch (or its hold-back creep) before the end."""
        if self.aircraft.flight.start == 'airborne':
            return "aircraft.flight.start is airborne (the aircraft is off the deck)"
        cat = self.aircraft.catapult
        start = cat.launch_time_s - (cat.holdback_s if cat.holdback_stretch_m > 0.0 else 0.0)
        if cat.enabled and start < self.duration_s:
            return (f"the catapult moves the aircraft from {start:g} s (aircraft.catapult.launch_time_s = "
                    f"{cat.launch_time_s:g} s), inside duration_s = {self.duration_s:g} s")
        return ''

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
    """The scenarios and params: $ALIGN_ROOT/config, else the source tree's (this file is
    src/alignment_core/alignment_core/config/scenario.py), else the installed copy in
    share/alignment_core/config (a colcon install without the repository)."""
    root = os.environ.get('ALIGN_ROOT')
    if root:
        return Path(root) / 'config'
    source = Path(__file__).resolve().parents[4] / 'config'
    if source.is_dir():
        return source
    try:
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory
    except ImportError:
        return source
    try:
        return Path(get_package_share_directory('alignment_core')) / 'config'
    except PackageNotFoundError:
        return source


def scenario_path(name_or_path: str) -> Path:
    p = Path(name_or_path)
    if p.suffix in ('.yaml', '.yml') and p.exists():
        return p
    cand = config_dir() / 'scenarios' / f'{name_or_path}.yaml'
    if cand.exists():
        return cand
    avail = sorted(x.stem for x in (config_dir() / 'scenarios').glob('*.yaml'))
    raise ConfigError(f"unknown scenario {name_or_path!r} (available: {', '.join(avail)})")


def parse_overrides(items: list[str] | tuple[str, ...]) -> dict[str, object]:
    """['ship.sea_state=6', ...] -> {'ship.sea_state': 6}; values parsed as YAML scalars."""
    out = {}
    for it in items:
        if '=' not in it:
            raise ConfigError(f"--set expects KEY=VALUE, got {it!r}")
        k, v = it.split('=', 1)
        out[k.strip()] = yaml.safe_load(v)
    return out


def resolve(given: dict | None, overrides: dict[str, object] | None = None,
            scope: Scope | None = None) -> Scenario:
    """The scenario `given` (nested) and the dotted `overrides` define: presets and the
    defaulting rules fill the keys not given (given.fill_defaults), then it is validated.
    With a scope (a node's keys), keys outside it are dropped after the rules, so they keep
    their defaults, and only the checks the scope allows run (Scenario.validate)."""
    data = fill_defaults(with_overrides(given, overrides), default_seed=Scenario.seed)
    if scope is None:
        return build(Scenario, data)
    return _build_within(within(data, scope), scope)


_HINTS = typing.get_type_hints(Scenario)
_SECTIONS = {f.name for f in dataclasses.fields(Scenario) if dataclasses.is_dataclass(_HINTS[f.name])}
_TopLevel = dataclasses.make_dataclass('TopLevel', [
    (f.name, _HINTS[f.name], dataclasses.field(default=f.default))
    for f in dataclasses.fields(Scenario) if f.name not in _SECTIONS])
"""The scenario's own keys (seed, rate_hz, ...), typed as in Scenario, checked by `build`."""


def _build_within(data: dict, scope: Scope) -> Scenario:
    """Each section built (type- and range-checked) on its own, then the scenario's checks
    that `scope` allows."""
    parts = {name: build(_HINTS[name], data.pop(name), name) for name in list(data) if name in _SECTIONS}
    top = build(_TopLevel, data)
    sc = Scenario(**{f.name: getattr(top, f.name) for f in dataclasses.fields(top)}, **parts)
    sc.validate(scope.covers)
    return sc


def from_dict(data: dict, overrides: dict[str, object] | None = None) -> Scenario:
    """The complete scenario of a nested mapping with dotted overrides (see `resolve`)."""
    return resolve(data, overrides)


def given_data(name_or_path: str, overrides: dict[str, object] | None = None,
               seed: int | None = None) -> dict:
    """What a scenario file and its overrides give, before presets and defaults (nested):
    `resolve` of it is `load`'s scenario; run_graph gives it to the nodes as parameters."""
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
    return with_overrides(data, ov)


def load(name_or_path: str, overrides: dict[str, object] | None = None,
         seed: int | None = None) -> Scenario:
    """Load a scenario by name (config/scenarios/NAME.yaml) or path, apply dotted overrides."""
    return resolve(given_data(name_or_path, overrides, seed))


def dump(sc: Scenario) -> str:
    return yaml.safe_dump(to_dict(sc), sort_keys=False)
