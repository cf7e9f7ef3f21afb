"""The aircraft's configuration (`aircraft.*`): deck spot, heading on deck, mounting, and the
catapult, vibration, flexure, flight and landing-gear sections (kinematics.py uses it)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from alignment_core.aircraft.catapult import CatapultConfig
from alignment_core.aircraft.deck_flexure import FlexureConfig
from alignment_core.aircraft.flight_config import FlightConfig
from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.aircraft.vibration import VibrationConfig
from alignment_core.validation import require


@dataclass(frozen=True)
class AircraftConfig:
    """Deck spot, heading on deck and mounting, catapult and flight. Default misalignment is
    seed 000's (10', 15', -30') in its right-forward-up axes, i.e. (15', -10', -30') in FLU
    (x fwd/roll, y left, z up/yaw). heading_on_deck_deg: the aircraft's (and the catapult
    track's) nominal heading from the ship's bow, clockwise (0: a bow catapult).
    misalignment_random_arcmin > 0 adds a random constant per axis (1-sigma, drawn once per seed
    from the stream 'mounting') to the given misalignment. lever_arm_survey_sigma_m > 0: the
    filter is told a lever arm off the true one by a random constant per axis (config/given.py)."""
    lever_arm_m: tuple[float, float, float] = (40.0, -10.0, 15.0)
    misalignment_arcmin: tuple[float, float, float] = (15.0, -10.0, -30.0)
    misalignment_random_arcmin: float = 0.0
    lever_arm_survey_sigma_m: float = 0.0   # 1-sigma survey error of filter.lever_arm_m (config/given.py)
    heading_on_deck_deg: float = 0.0
    catapult: CatapultConfig = field(default_factory=CatapultConfig)
    vibration: VibrationConfig = field(default_factory=VibrationConfig)
    flexure: FlexureConfig = field(default_factory=FlexureConfig)
    flight: FlightConfig = field(default_factory=FlightConfig)
    gear: GearConfig = field(default_factory=GearConfig)

    def validate(self) -> None:
        r = np.asarray(self.lever_arm_m)
        require(np.hypot(r[0], r[1]) <= 200.0 and abs(r[2]) <= 50.0,
                f"lever_arm_m out of range (|horizontal| <= 200 m, |z| <= 50 m): {self.lever_arm_m}")
        require(bool(np.all(np.abs(self.misalignment_arcmin) <= 600.0)),
                f"misalignment_arcmin must be within +-600' per axis: {self.misalignment_arcmin}")
        require(0.0 <= self.misalignment_random_arcmin <= 120.0,
                f"misalignment_random_arcmin must be in [0, 120], got {self.misalignment_random_arcmin}")
        require(-180.0 <= self.heading_on_deck_deg <= 180.0,
                f"heading_on_deck_deg must be in [-180, 180], got {self.heading_on_deck_deg}")
        require(0.0 <= self.lever_arm_survey_sigma_m <= 10.0,
                f"lever_arm_survey_sigma_m must be in [0, 10] m, got {self.lever_arm_survey_sigma_m}")
        require(self.flight.start == 'deck' or not self.catapult.enabled,
                "flight.start airborne has no deck phase: set catapult.enabled false")
