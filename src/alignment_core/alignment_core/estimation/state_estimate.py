"""The whole estimate, labelled (docs/engine.md, outputs): every state of the model as what the
filter has accumulated so far, in SI units with the unit in the label, for /alignment/state and
summary.json. A closed-loop filter feeds some states back after each update (the sensor
biases, the mounting, the lever arm: into the engine's corrections; attitude and velocity: into
the slave solution, leaving a residual) and keeps the others in its state (flexure, master
attitude error, delay, the Doppler radar's errors). The accumulated estimate of a state is its
correction so far plus what the filter's state holds now; its 1-sigma is the state's (the
corrections are known numbers). Attitude and velocity are reported as their residual error
(zero right after an update): their estimate is the corrected slave solution itself."""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import Corrections

_NDARRAY = np.ndarray
_INF = float('inf')

# model label prefix -> (published name, unit suffix, the correction it accumulates into, if any)
_KINDS: dict[str, tuple[str, str, str | None]] = {
    'phi': ('attitude_error', 'rad', None),
    'dV': ('velocity_error', 'mps', None),
    'eps': ('gyro_bias', 'radps', 'bg'),
    'nabla': ('accel_bias', 'mps2', 'ba'),
    'mu': ('mounting', 'rad', 'mu'),
    'theta': ('flexure', 'rad', None),
    'thetadot': ('flexure_rate', 'radps', None),
    'phim': ('master_attitude_error', 'rad', None),
    'dr': ('lever_arm_error', 'm', 'dr'),
}
_SINGLE: dict[str, str] = {             # labels without an axis
    'dt_master': 'master_delay_s',
    'dlon': 'position_error_lon_rad',
    'dlat': 'position_error_lat_rad',
    'dVd': 'doppler_velocity_offset_mps',
    'eps_D': 'doppler_track_angle_error_rad',
    'dC': 'doppler_scale_factor_error_ratio',
}
_AXES = {'x': 0, 'y': 1, 'z': 2, 'E': 0, 'N': 1, 'U': 2}


class StateEstimate:
    """The map from a model's state labels to the published ones and their corrections."""

    def __init__(self, labels: tuple[str, ...]) -> None:
        names: list[str] = []
        self._fed: list[tuple[int, str, int]] = []     # (state index, correction, axis)
        for i, lab in enumerate(labels):
            if lab in _SINGLE:
                names.append(_SINGLE[lab])
                continue
            prefix, _, axis = lab.rpartition('_')
            if prefix not in _KINDS or axis not in _AXES:
                raise ValueError(f'state {lab!r}: no published name (estimation/state_estimate.py)')
            name, unit, corr = _KINDS[prefix]
            names.append(f'{name}_{axis}_{unit}')
            if corr is not None:
                self._fed.append((i, corr, _AXES[axis]))
        self.labels = tuple(names)
        self._names = tuple(dict.fromkeys(name for _, name, _ in self._fed))

    def values(self, x: np.ndarray, corr: Corrections) -> np.ndarray:
        """(n,) the accumulated estimate: the filter's state x (after feedback) plus the corrections."""
        out = np.array(x, dtype=float)
        fed = {name: getattr(corr, name) for name in self._names}
        if out.ndim != 1 or not all(type(c) is _NDARRAY and c.dtype.char in 'fd' for c in fed.values()):
            for i, name, axis in self._fed:
                out[i] += fed[name][axis]
            return out
        sums = out.tolist()                 # Python floats: numpy's sums, a third of its time
        cells = {name: c.tolist() for name, c in fed.items()}
        for i, name, axis in self._fed:
            v = sums[i] + cells[name][axis]
            if not -_INF < v < _INF:        # numpy's own sum: its NaN, and its warning (or error) on overflow
                v = float(out[i] + fed[name][axis])
            sums[i] = v
        return np.array(sums)
