"""A day's departure from the standard atmosphere (air_data/atmosphere.py): the offsets a
scenario names, apart from the atmosphere itself so that loading a scenario does not load it."""
from __future__ import annotations

from dataclasses import dataclass

from alignment_core.validation import require


@dataclass(frozen=True)
class DayOffsets:
    """The day's departure from the standard atmosphere: dT added to the temperature at every
    geopotential height (K), dp0 added to the sea-level pressure (Pa)."""
    delta_t_k: float = 0.0
    delta_p0_pa: float = 0.0

    def validate(self) -> None:
        require(-80.0 <= self.delta_t_k <= 80.0, f"delta_t_k must be in [-80, 80] K, got {self.delta_t_k}")
        require(-20000.0 <= self.delta_p0_pa <= 20000.0,
                f"delta_p0_pa must be in [-20000, 20000] Pa, got {self.delta_p0_pa}")


STANDARD_DAY = DayOffsets()
