"""/alignment/state read by its labels, whatever the model: rows named in ``layout.dim[0].label``
('t_s|value|sigma|mu_sigma'), states in ``layout.dim[1].label`` (comma separated). Readers (the
progress line, the plots) look rows and states up by name, so a layout with other row or state
names (unit-suffixed ones, an accumulated estimate instead of the error state) reads too, and
the units each state is drawn in come from its name (:func:`display_unit`)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
DEG_PER_RAD = 180.0 / math.pi
G0 = 9.80665

# name suffix -> (display unit, factor from the SI value): unit-labelled state names
SUFFIX_UNITS = (
    ('_radps', ('deg/h', DEG_PER_RAD * 3600.0)), ('_rad_s', ('deg/h', DEG_PER_RAD * 3600.0)),
    ('_dph', ('deg/h', 1.0)), ('_mps2', ('mg', 1e3 / G0)), ('_mg', ('mg', 1.0)),
    ('_mps', ('m/s', 1.0)), ('_rad', ('arcmin', ARCMIN_PER_RAD)), ('_arcmin', ('arcmin', 1.0)),
    ('_ms', ('ms', 1.0)), ('_s', ('ms', 1e3)), ('_m', ('m', 1.0)), ('_ratio', ('ppm', 1e6)),
)
# name prefix -> display unit, factor: the models' short names (phi_E, dV_N, eps_x, nabla_y, ...)
PREFIX_UNITS = (
    ('thetadot', ('deg/h', DEG_PER_RAD * 3600.0)), ('theta', ('arcmin', ARCMIN_PER_RAD)),
    ('phim', ('arcmin', ARCMIN_PER_RAD)), ('phi', ('arcmin', ARCMIN_PER_RAD)),
    ('mu', ('arcmin', ARCMIN_PER_RAD)), ('dV', ('m/s', 1.0)), ('eps', ('deg/h', DEG_PER_RAD * 3600.0)),
    ('nabla', ('mg', 1e3 / G0)), ('dt', ('ms', 1e3)), ('dr', ('m', 1.0)), ('lever', ('m', 1.0)),
    ('dlat', ('arcmin', ARCMIN_PER_RAD)), ('dlon', ('arcmin', ARCMIN_PER_RAD)),
)


def display_unit(label: str) -> tuple[str, float]:
    """(unit, factor) a state named `label` is shown in (value_shown = value_SI * factor);
    ('', 1.0) when the name says nothing of its unit."""
    for suffix, unit in SUFFIX_UNITS:
        if label.endswith(suffix):
            return unit
    for prefix, unit in PREFIX_UNITS:
        if label.startswith(prefix):
            return unit
    return '', 1.0


def group_of(label: str) -> str:
    """The family a state belongs to (its name without the axis: 'eps_x' -> 'eps',
    'gyro_bias_x_radps' -> 'gyro_bias'); states of one family share a panel."""
    for suffix, _ in SUFFIX_UNITS:
        if label.endswith(suffix):
            label = label[:-len(suffix)]
            break
    head, sep, tail = label.rpartition('_')
    if sep and tail in ('x', 'y', 'z', 'E', 'N', 'U', 'e', 'n', 'u', 'east', 'north', 'up'):
        return head
    return label


@dataclass(frozen=True)
class StateRecord:
    """One /alignment/state message: its rows by name, each an array over `labels`."""
    rows: dict[str, np.ndarray]
    labels: tuple[str, ...]

    @property
    def t_s(self) -> float | None:
        for name in ('t_s', 'stamp_s', 't'):
            if name in self.rows:
                return float(self.rows[name][0])
        return None

    def misalignment_sigma(self) -> np.ndarray | None:
        """The misalignment's 1-sigma (3,) rad: the 'mu_sigma' row's first three, or the sigma
        row of states named misalignment_*; None if the layout has neither."""
        for name in ('mu_sigma', 'misalignment_sigma', 'misalignment_sigma_rad'):
            if name in self.rows:
                return self.rows[name][:3]
        idx = [i for i, n in enumerate(self.labels) if n.startswith('misalignment')]
        sig = self.rows.get('sigma')
        if len(idx) == 3 and sig is not None:
            return sig[idx]
        return None


def parse(dims: list[tuple[str, int]], data) -> StateRecord:
    """A StateRecord from the layout's (label, size) dimensions and the flat data; ValueError
    if they do not fit."""
    if len(dims) < 2:
        raise ValueError('/alignment/state needs two layout dimensions (rows, states)')
    rows = dims[0][0].split('|')
    labels = tuple(dims[1][0].split(','))
    arr = np.asarray(data, dtype=float)
    if arr.size != len(rows) * len(labels):
        raise ValueError(f'/alignment/state: {arr.size} values for {len(rows)} rows x {len(labels)} states')
    arr = arr.reshape(len(rows), len(labels))
    return StateRecord({r: arr[i] for i, r in enumerate(rows)}, labels)


def from_msg(m) -> StateRecord:
    """A StateRecord of a std_msgs/Float64MultiArray."""
    return parse([(d.label, d.size) for d in m.layout.dim], m.data)
