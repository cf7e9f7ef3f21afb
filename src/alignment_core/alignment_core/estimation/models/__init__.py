"""Error-state models for transfer alignment, behind one interface (base.ErrorModel), selected at
run time by `filter.model`:

    vm15                 velocity_matching.py  phi, dV, eps, nabla, master attitude phi_m (default)
    vm12                 velocity_matching.py  phi, dV, eps, nabla
    seed000_6            seed000.py            phi, dV (seed 000, small angle)
    seed000_large_angle  seed000.py            phi (rotation vector, any size), dV; nonlinear
    seed002_10           seed002.py            dV_E, dV_N, phi, nabla_x, nabla_y, eps (horizontal)
    seed003_21           seed003.py            phi, dV, eps, nabla, mounting mu, flexure theta, theta';
                                               velocity + attitude matching
    seed003_24           seed003.py            seed003_21 + master attitude phi_m
    seed001_13           seed001.py            phi, dV_E, dV_N, position, eps, Doppler errors: deck LDV
                                               matching, then Doppler radar matching in flight

Options, each a wrapper around the model (applied in this order):
    filter.attitude_match_axes: yaw   yaw_matching.py    seed003_*: velocity + heading match only
    filter.rate_matching: true        rate_matching.py   + 3 angular-rate rows (models with phi, eps)
    filter.master_delay_state: true   master_delay.py    + dt_master, the master's unknown latency
    filter.lever_arm_states: true     lever_arm.py       + dr (3), the lever arm's error
Matching modes: velocity (all), + attitude (seed003_*) or + yaw only, + angular rate, + Doppler
radar velocity (seed001_13).
"""
from __future__ import annotations

from alignment_core.estimation.models.base import Corrections, ErrorModel, Match, Measurement, Propagation
from alignment_core.estimation.models.lever_arm import LeverArmStates
from alignment_core.estimation.models.master_delay import MasterDelayState
from alignment_core.estimation.models.rate_matching import RateMatching
from alignment_core.estimation.models.seed000 import Seed000LargeAngle, Seed000Linear
from alignment_core.estimation.models.seed001 import DopplerTuning, Seed001Doppler
from alignment_core.estimation.models.seed002 import Seed002Horizontal
from alignment_core.estimation.models.seed003 import Seed003VelocityAttitude
from alignment_core.estimation.models.velocity_matching import VelocityMatching, noise_densities
from alignment_core.estimation.models.yaw_matching import YawMatching
from alignment_core.units import DPH

MODELS = ('vm15', 'vm12', 'seed000_6', 'seed000_large_angle', 'seed002_10', 'seed003_21', 'seed003_24',
          'seed001_13')
NONLINEAR_MODELS = ('seed000_large_angle',)
DOPPLER_MODELS = ('seed001_13',)       # need doppler.enabled (the /doppler/twist stream)

__all__ = ['Corrections', 'ErrorModel', 'Match', 'Measurement', 'Propagation', 'MODELS', 'NONLINEAR_MODELS',
           'DOPPLER_MODELS', 'make_model']


def make_model(cfg) -> ErrorModel:
    """The engine's error model for a FilterConfig (`model`, `lever_arm_states`)."""
    name = cfg.model
    if name in ('vm15', 'vm12'):
        base: ErrorModel = VelocityMatching(cfg, master_states=name == 'vm15')
    elif name == 'seed000_6':
        base = Seed000Linear(cfg)
    elif name == 'seed000_large_angle':
        base = Seed000LargeAngle(cfg)
    elif name == 'seed002_10':
        base = Seed002Horizontal(cfg)
    elif name in ('seed003_21', 'seed003_24'):
        base = Seed003VelocityAttitude(cfg, master_states=name == 'seed003_24')
    elif name == 'seed001_13':
        base = Seed001Doppler(DopplerTuning.from_config(cfg))
    else:
        raise ValueError(f'model {name!r} cannot run in the transfer-alignment engine')
    if cfg.attitude_match_axes == 'yaw':
        base = YawMatching(base)
    if cfg.rate_matching:
        base = RateMatching(base, noise_densities(cfg).arw, cfg.rate_match_sigma_dph * DPH)
    if cfg.master_delay_state:
        base = MasterDelayState(base, cfg.master_delay_sigma_ms * 1e-3)
    if cfg.lever_arm_states:
        return LeverArmStates(base, cfg.lever_arm_sigma_m)
    return base
