"""The port pressures a state predicts, for a batch of states at once (the sigma-point filters
evaluate all their points in one call): the INS flight at each port's sensing instant, the
air-mass velocity of the state, the day's atmosphere, the port model, the port's bias and
correlated noise."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.air_data import standard_day
from alignment_core.air_data.atmosphere import GAMMA, R_AIR
from alignment_core.air_data.flow_angles import air_angles
from alignment_core.air_data.pitot import impact_pressure_ratio
from alignment_core.air_data.ports import PortModel
from alignment_core.estimation.air_data import turbulence_model
from alignment_core.estimation.air_data.inputs import InsAt


@dataclass(frozen=True)
class StateLayout:
    """Indices of the tight form's state: wind (3, ENU), turbulence (5, turbulence_model.py, if
    modelled),
    static-pressure ratio offset, temperature offset (K), port biases (n, Pa), port noise (n, Pa)."""
    ports: int
    turbulence: bool

    @property
    def wind(self) -> slice:
        return slice(0, 3)

    @property
    def turb(self) -> slice:
        return slice(3, 3 + turbulence_model.SIZE) if self.turbulence else slice(3, 3)

    @property
    def static(self) -> int:
        return self.turb.stop

    @property
    def temperature(self) -> int:
        return self.static + 1

    @property
    def bias(self) -> slice:
        return slice(self.temperature + 1, self.temperature + 1 + self.ports)

    @property
    def noise(self) -> slice:
        return slice(self.bias.stop, self.bias.stop + self.ports)

    @property
    def size(self) -> int:
        return self.noise.stop

    def labels(self) -> tuple[str, ...]:
        out = ['wind_state_east_mps', 'wind_state_north_mps', 'wind_state_up_mps']
        if self.turbulence:
            out += list(turbulence_model.LABELS)
        out += ['static_offset', 'temperature_offset_k']
        out += [f'bias_port_{k}_pa' for k in range(self.ports)]
        out += [f'noise_port_{k}_pa' for k in range(self.ports)]
        return tuple(out)


def air_mass_velocity(x: np.ndarray, layout: StateLayout, turb_map: np.ndarray | None) -> np.ndarray:
    """Wind plus turbulence (N, 3) ENU of states (N, n); turb_map (3, 5) from the turbulence
    state (turbulence_model.TurbulenceModel.at)."""
    w = x[:, layout.wind]
    return w + x[:, layout.turb] @ turb_map.T if layout.turbulence and turb_map is not None else w


def static_pressure(x: np.ndarray, layout: StateLayout, height_m: np.ndarray) -> np.ndarray:
    """p_inf (N, m) of states x (N, n) at INS heights (m,): the hydrostatic pressure of a day
    warmer by the temperature offset, times 1 + the static ratio offset (the sea-level pressure
    of the day and the INS height error)."""
    return standard_day.day_pressure(height_m, x[:, layout.temperature]) * (1.0 + x[:, layout.static, None])


def air_data_of(x: np.ndarray, layout: StateLayout, c_bn: np.ndarray, v_enu: np.ndarray,
                t_std: float, height_m: float, turb_map: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Air data of states x (N, n) flying with C_b^n (3, 3), ground velocity v_enu (3,) at the
    INS height (standard temperature t_std there): v_air_body (N, 3), speed, alpha, beta,
    temperature, p_inf, mach, qc (N,)."""
    v_air_n = v_enu[None, :] - air_mass_velocity(x, layout, turb_map)
    v_air_b = v_air_n @ c_bn                                  # C_n^b v = (v^T C_b^n)
    speed, alpha, beta = air_angles(v_air_b)
    temperature = t_std + x[:, layout.temperature]
    p_inf = static_pressure(x, layout, np.array([height_m]))[:, 0]
    mach = speed / np.sqrt(GAMMA * R_AIR * np.maximum(temperature, 1.0))
    qc = impact_pressure_ratio(mach) * p_inf
    return {'v_air_body': v_air_b, 'speed': speed, 'alpha': alpha, 'beta': beta, 'temperature': temperature,
            'p_inf': p_inf, 'mach': mach, 'qc': qc}


LAG_NODES, LAG_WEIGHTS = np.polynomial.laguerre.laggauss(3)
"""A port behind a first-order pneumatic lag tau reads int_0^inf e^(-s/tau) p(t - s) ds / tau:
three-point Gauss-Laguerre in s = tau u is exact for p polynomial in s to degree 5."""


def lag_instants(t: float, taus: np.ndarray) -> np.ndarray:
    """The instants (m * J,) at which each of m ports (lag taus (m,)) samples the flight: port
    by port, then node by node."""
    return (t - np.asarray(taus, dtype=float)[:, None] * LAG_NODES[None, :]).reshape(-1)


class PortPrediction:
    """h(x) of one frame: the used ports' pressures (N, m) for states (N, n), each port the
    lag-weighted mean of the model pressure over its recent past (the flight at the instants of
    `lag_instants`, weights LAG_WEIGHTS); a single instant per port (J = 1) means no lag."""
    vectorized = True

    def __init__(self, model: PortModel, layout: StateLayout, ports: np.ndarray, ins: InsAt,
                 turb_maps: np.ndarray | None = None) -> None:
        """turb_maps (m J, 3, 5): the ENU turbulence at each sensing instant from the state's
        turbulence at the frame time (turbulence_model.TurbulenceModel.looking_back)."""
        self.model, self.layout, self.ports = model, layout, np.asarray(ports, dtype=int)
        self.turb_maps = turb_maps
        m = self.ports.size
        self.nodes = len(ins.height_m) // m
        self.weights = LAG_WEIGHTS if self.nodes == LAG_NODES.size else np.ones(1)
        self.normals = np.repeat(model.geometry.normals[self.ports], self.nodes, axis=0)    # (m J, 3)
        self.c_bn, self.v_enu = ins.c_bn, ins.v_enu                 # (m J, 3, 3), (m J, 3)
        self.height_m = ins.height_m
        self.t_std, _ = standard_day.temperature_pressure(ins.height_m)      # (m J,)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        lay = self.layout
        air = x[:, lay.wind][:, None, :]
        if lay.turbulence and self.turb_maps is not None:
            air = air + np.einsum('mik,nk->nmi', self.turb_maps, x[:, lay.turb])
        v_air_n = self.v_enu[None, :, :] - air                                          # (N, m J, 3)        # (N, m, 3)
        v_air_b = np.einsum('nmj,mji->nmi', v_air_n, self.c_bn)
        speed = np.linalg.norm(v_air_b, axis=-1)
        cos_sigma = np.einsum('nmi,mi->nm', v_air_b, self.normals) / np.maximum(speed, 1e-9)
        temperature = np.maximum(self.t_std[None, :] + x[:, lay.temperature, None], 1.0)
        p_inf = static_pressure(x, lay, self.height_m)
        mach = speed / np.sqrt(GAMMA * R_AIR * temperature)
        qc = impact_pressure_ratio(mach) * p_inf
        c2 = cos_sigma**2
        eps = self.model.epsilon(mach)
        sensed = (qc * (c2 + eps * (1.0 - c2)) + p_inf).reshape(len(x), self.ports.size, self.nodes) @ self.weights
        return sensed + x[:, lay.bias][:, self.ports] + x[:, lay.noise][:, self.ports]
