"""A synthetic flight for the air-data estimator tests: a level flight at constant airspeed with
gentle heading and pitch oscillations (so wind separates from the day's offsets), a constant
wind, a perfect INS, and port pressures from the port model with white or first-order
Gauss-Markov noise (no lag). Independent of the FADS sensor stage."""
from __future__ import annotations

import math
from dataclasses import dataclass

import ambiance
import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.air_data.ports import PortModel
from alignment_core.estimation.air_data.inputs import InsSample


@dataclass
class Frame:
    t: float
    ins: InsSample
    pressures: np.ndarray
    alpha: float
    beta: float
    mach: float
    p_inf: float
    v_air_body: np.ndarray


def air_angles_frd(v_flu: np.ndarray) -> tuple[float, float, float]:
    """Speed, alpha, beta by the textbook FRD formulas (u, v, w) = (x, -y, -z) of FLU."""
    u, v, w = v_flu[0], -v_flu[1], -v_flu[2]
    speed = math.sqrt(u * u + v * v + w * w)
    return speed, math.atan2(w, u), math.asin(v / speed)


def flight(duration_s=300.0, rate_hz=10.0, height_m=10000.0, mach=0.8, wind=(5.0, -3.0, 0.0), sigma_pa=20.0,
           rho=0.0, bias_pa=(0.0,) * 5, delta_t_k=0.0, seed=1, model=None, turn_amplitude_rad=0.3):
    model = model or PortModel()
    rng = np.random.default_rng(seed)
    atm = ambiance.Atmosphere(height_m)
    t_day = float(atm.temperature[0]) + delta_t_k
    p_inf = float(atm.pressure[0])
    a = math.sqrt(1.4 * 287.05287 * t_day)
    wind = np.asarray(wind, dtype=float)
    noise = rng.standard_normal(5) * sigma_pa
    out = []
    for k in range(int(duration_s * rate_hz)):
        t = k / rate_hz
        yaw = math.radians(90.0) + turn_amplitude_rad * math.sin(2 * math.pi * t / 120.0)
        pitch = math.radians(3.0) + math.radians(2.0) * math.sin(2 * math.pi * t / 40.0)
        roll = 0.1 * math.sin(t / 10.0)
        q = Rotation.from_euler('ZYX', [yaw, -pitch, roll]).as_quat()
        v_air_n = mach * a * np.array([math.cos(yaw), math.sin(yaw), 0.0])
        v_g = v_air_n + wind
        v_air_b = Rotation.from_quat(q).as_matrix().T @ v_air_n
        speed, alpha, beta = air_angles_frd(v_air_b)
        clean = model.pressures(alpha, beta, speed / a, p_inf)
        noise = rho * noise + math.sqrt(1.0 - rho * rho) * sigma_pa * rng.standard_normal(5)
        ins = InsSample(t, q, v_g, height_m, math.radians(30.0))
        out.append(Frame(t, ins, clean + noise + np.asarray(bias_pa), alpha, beta, speed / a, p_inf, v_air_b))
    return out
