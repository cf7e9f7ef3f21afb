"""Sensor error models (re-exported from their modules, so `from .sensors import ...` keeps
working): slave IMU (imu_errors), master INS (master_ins), laser Doppler velocimeter (ldv),
Doppler radar (doppler_radar), named grades (sensor_presets), output rate and latency
(sensor_timing)."""
from __future__ import annotations

from .doppler_radar import DopplerConfig, DopplerRadarModel, DopplerSample, DopplerStage
from .imu_errors import UG, ImuConfig, ImuErrorModel, Quantiser
from .ldv import LdvConfig, LdvModel, LdvStage
from .master_ins import MasterConfig, MasterInsModel, MasterInsStage, MasterOutput, SchulerErrorModel
from .sensor_presets import IMU_PRESETS, MASTER_PRESETS
from .sensor_timing import SensorTiming

__all__ = ['UG', 'DopplerConfig', 'DopplerRadarModel', 'DopplerSample', 'DopplerStage', 'ImuConfig',
           'ImuErrorModel', 'Quantiser', 'LdvConfig', 'LdvModel', 'LdvStage', 'MasterConfig',
           'MasterInsModel', 'MasterInsStage', 'MasterOutput', 'SchulerErrorModel', 'IMU_PRESETS',
           'MASTER_PRESETS', 'SensorTiming']
