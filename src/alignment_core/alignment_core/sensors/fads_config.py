"""Configuration of the flush air-data sensor (scenario section `fads`) and its fault list.

Fault syntax (`faults`, one string; items separated by ';' or new lines, ports numbered
0..n-1 as in air_data/ports.py, times in seconds after the stage's t0, the scenario start):
    blocked   port=P at_s=T           the port's line is blocked: its pressure stays at the
                                      (lagged) value it had at T; noise and bias still add
    bias_step port=P at_s=T pa=X      X Pa added to the port from T on (steps add up)
    noise     port=P at_s=T factor=F  the port's noise (additive and multiplicative) scaled
                                      by F >= 0 from T on (a later noise fault replaces it)
e.g. "blocked port=2 at_s=500; bias_step port=1 at_s=300 pa=200; noise port=3 at_s=100 factor=5".
"""
from __future__ import annotations

from dataclasses import dataclass, field

from alignment_core.air_data.day_offsets import DayOffsets
from alignment_core.air_data.port_layout import EpsilonCalibration, PortGeometry
from alignment_core.aircraft.wind import WindConfig
from alignment_core.validation import keyed_items, require

FAULT_KINDS = ('blocked', 'bias_step', 'noise')
FAULT_KEYS = {'blocked': ('port', 'at_s'), 'bias_step': ('port', 'at_s', 'pa'),
              'noise': ('port', 'at_s', 'factor')}
_GEOMETRY, _EPSILON = PortGeometry(), EpsilonCalibration()


@dataclass(frozen=True)
class FadsFault:
    """One parsed fault (see the module docstring); `pa` / `factor` only for their kinds."""
    kind: str
    port: int
    at_s: float
    pa: float = 0.0
    factor: float = 1.0


def parse_faults(text: str, n_ports: int) -> tuple[FadsFault, ...]:
    """Parse and check a fault string; ConfigError names the fault and the problem."""
    out: list[FadsFault] = []
    for where, kind, vals in keyed_items(text, 'faults', 'fault', {k: FAULT_KEYS[k] for k in FAULT_KINDS}):
        missing = [k for k in FAULT_KEYS[kind] if k not in vals]
        require(not missing, f"{where}: {kind} needs {', '.join(missing)}")
        port = vals.pop('port')
        require(port == int(port) and 0 <= port < n_ports,
                f"{where}: port must be an integer in [0, {n_ports - 1}], got {port:g}")
        require(0.0 <= vals['at_s'] <= 1e7, f"{where}: at_s must be in [0, 1e7] s, got {vals['at_s']}")
        require(abs(vals.get('pa', 0.0)) <= 1e6, f"{where}: pa must be within +-1e6 Pa, got {vals.get('pa')}")
        require(0.0 <= vals.get('factor', 1.0) <= 1e4, f"{where}: factor must be in [0, 1e4], got {vals.get('factor')}")
        fault = FadsFault(kind=kind, port=int(port), **vals)
        require(kind != 'blocked' or all(f.kind != 'blocked' or f.port != fault.port for f in out),
                f"{where}: port {fault.port} is blocked twice")
        out.append(fault)
    return tuple(out)


@dataclass(frozen=True)
class FadsConfig:
    """Flush air-data sensor: port pressures of the nose (air_data/ports.py) at its own rate,
    through a pneumatic lag, with Gauss-Markov noise, biases and faults (sensors/fads.py).
    - rate_hz: frame rate (own grid from t0, not tied to the scenario rate; the period
      is rounded to whole nanoseconds: `period_ns`);
    - cone_deg, clock_deg: port geometry; eps_mach, eps: the eps(M) table (same defaults as
      PortGeometry and EpsilonCalibration, air_data/port_layout.py);
    - sigma_pa: additive first-order Gauss-Markov noise per port (1-sigma, stationary);
      scale_sigma: multiplicative one (relative, 1-sigma); both with lag-1 correlation
      `noise_correlation` at the frame interval (seed 004's "correlation 0.5");
    - bias_pa: constant bias per port (empty: zeros); bias_sigma_pa: a random constant per
      port on top (1-sigma, drawn once per seed);
    - lag_s_sea_level: pneumatic lag tau0 (s, 0 = none), tau = tau0 p0 / p_inf;
    - min_airspeed_mps: no frame below this true airspeed (a FADS needs airflow);
    - day: the atmosphere's offsets; wind: the wind truth the stage owns (mean + Dryden);
    - faults: the fault list (module docstring)."""
    enabled: bool = False
    rate_hz: float = 1.0
    cone_deg: tuple[float, ...] = _GEOMETRY.cone_deg
    clock_deg: tuple[float, ...] = _GEOMETRY.clock_deg
    eps_mach: tuple[float, ...] = _EPSILON.mach
    eps: tuple[float, ...] = _EPSILON.eps
    sigma_pa: float = 20.0
    scale_sigma: float = 0.0
    noise_correlation: float = 0.5
    bias_pa: tuple[float, ...] = ()
    bias_sigma_pa: float = 0.0
    lag_s_sea_level: float = 0.02
    min_airspeed_mps: float = 10.0
    day: DayOffsets = field(default_factory=DayOffsets)
    wind: WindConfig = field(default_factory=WindConfig)
    faults: str = ''

    def validate(self) -> None:
        require(0.0 < self.rate_hz <= 1000.0, f"rate_hz must be in (0, 1000], got {self.rate_hz}")
        self.geometry.validate()
        self.epsilon.validate()
        require(0.0 <= self.sigma_pa <= 1e5, f"sigma_pa must be in [0, 1e5], got {self.sigma_pa}")
        require(0.0 <= self.scale_sigma <= 0.5, f"scale_sigma must be in [0, 0.5], got {self.scale_sigma}")
        require(0.0 <= self.noise_correlation < 1.0,
                f"noise_correlation must be in [0, 1), got {self.noise_correlation}")
        n = self.geometry.count
        require(len(self.bias_pa) in (0, n),
                f"bias_pa needs {n} values (one per port) or none, got {len(self.bias_pa)}")
        require(all(abs(b) <= 1e6 for b in self.bias_pa), f"bias_pa must be within +-1e6 Pa: {self.bias_pa}")
        require(0.0 <= self.bias_sigma_pa <= 1e5, f"bias_sigma_pa must be in [0, 1e5], got {self.bias_sigma_pa}")
        require(0.0 <= self.lag_s_sea_level <= 10.0,
                f"lag_s_sea_level must be in [0, 10] s, got {self.lag_s_sea_level}")
        require(0.0 <= self.min_airspeed_mps <= 1000.0,
                f"min_airspeed_mps must be in [0, 1000], got {self.min_airspeed_mps}")
        self.day.validate()
        self.wind.validate()
        parse_faults(self.faults, n)

    @property
    def geometry(self) -> PortGeometry:
        return PortGeometry(cone_deg=self.cone_deg, clock_deg=self.clock_deg)

    @property
    def epsilon(self) -> EpsilonCalibration:
        return EpsilonCalibration(mach=self.eps_mach, eps=self.eps)

    @property
    def period_ns(self) -> int:
        return int(round(1e9 / self.rate_hz))

    def parsed_faults(self) -> tuple[FadsFault, ...]:
        return parse_faults(self.faults, self.geometry.count)
