"""Where the slave's velocity relative to the master's body comes from (`filter.relative_velocity`,
docs/engine.md): the LDV (`ldv`), or nothing because the slave is rigidly tied to the master's
body (`zero`: relative velocity zero with white noise `rigid_velocity_sigma_mps`), or the LDV
while there is one (`auto`, the default).

Absence and silence are decided on stamps: the LDV stream is silent when the IMU and the
master (the least advanced of them) have both run `ldv_silence_s` past the newest stamp of any
stream when the LDV last delivered (its last stamp when it arrives in step with the others), or
past the first stamp of any stream when no LDV sample came at all. An LDV that runs behind the
others on arrival but keeps delivering is never taken for silent, so the graph and the batch
agree; and since processing waits for the LDV until then, when it is declared silent does not
change what is processed. The engine then stops waiting for it (it never stalls on an LDV):
- no LDV sample ever, under `auto`: relative velocity zero for the whole run ('zero (no LDV
  stream)'; nothing was processed before, the engine waited for the stream);
- an LDV that fell silent mid-run: matches after its last sample are made as parked (zero
  relative velocity, the parked noise) under `auto` while the aircraft has not moved, and not
  at all once it moved or under `ldv` (free inertial). A silenced LDV is not taken back.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.config import FilterConfig
from alignment_core.navigation.history import LdvRecord

LDV, ZERO, ABSENT, SILENT = 'ldv', 'zero', 'zero (no LDV stream)', 'ldv silent'


class RelativeVelocity:
    """The engine's LDV presence: the mode now, the silence test and the stand-in record."""

    def __init__(self, cfg: FilterConfig) -> None:
        self.option = cfg.relative_velocity
        self.mode = ZERO if cfg.relative_velocity == 'zero' else LDV
        self._silence_ns = int(round(cfg.ldv_silence_s * 1e9))
        self.t_silent_ns: int | None = None     # the last LDV stamp when it was declared silent

    @property
    def takes_ldv(self) -> bool:
        """LDV samples are queued (not in zero mode, nor after the stream was declared silent)."""
        return self.mode == LDV

    @property
    def rigid(self) -> bool:
        """Every match is made with zero relative velocity and the rigid-mount noise."""
        return self.mode in (ZERO, ABSENT)

    def silent(self, last: dict[str, int | None], quiet_since_ns: int | None, final: bool = False) -> bool:
        """True (once) when the LDV stream is to be declared silent: the IMU and master stamps
        `last` (their latest; `last['ldv']` the LDV's) have both run ldv_silence_s past
        quiet_since_ns (the newest stamp of any stream when the LDV last delivered, or the first
        stamp if it never did); at the end of the data (final), under `auto`, when no LDV sample
        came at all."""
        if self.mode != LDV or quiet_since_ns is None:
            return False
        t_imu, t_master = last.get('imu'), last.get('master')
        if t_imu is None or t_master is None:
            return False
        ref = last.get('ldv')
        ended = final and ref is None and self.option == 'auto'
        if not ended and min(t_imu, t_master) - quiet_since_ns <= self._silence_ns:
            return False
        if ref is None and self.option == 'auto':
            self.mode = ABSENT
        else:
            self.mode = SILENT
            self.t_silent_ns = ref
        return True

    def stand_in(self, t_v: int, latest_ns: int | None, moving: bool, disp: np.ndarray) -> LdvRecord | None:
        """The record a match at validity time t_v uses when the LDV history cannot answer:
        zero relative velocity (parked) in rigid mode, or after a silent LDV's last sample under
        `auto` while parked; None: no match."""
        if self.rigid:
            return LdvRecord(t_v, np.zeros(3), True, False, disp)
        if self.mode == SILENT and self.option == 'auto' and not moving and (latest_ns is None or t_v > latest_ns):
            return LdvRecord(t_v, np.zeros(3), True, False, disp)
        return None

    def waits(self) -> bool:
        """Master matches wait for the LDV to reach their validity time."""
        return self.mode == LDV
