"""The engine's health as one level and its reasons (docs/engine.md, health and diagnostics).

ERROR: the filter broke down numerically, the consistency monitor's ERROR (persisting), or an
IMU gap longer than `gap_error_s` until the filter has re-converged (a full NIS window after
the gap within its bound). WARN: a shorter bridged gap (until the same), a failing NIS window,
a master or LDV that fell silent, or any input rejected or unmatched so far."""
from __future__ import annotations

from dataclasses import dataclass

from alignment_core.estimation.consistency import NisMonitor, WindowResult
from alignment_core.estimation.health import ERROR, OK, WARN
from alignment_core.estimation.outputs import Counters, Report


@dataclass
class Health:
    """What the engine knows of its own state beyond the consistency monitor."""
    running: bool = True              # False after a numerical breakdown (the filter stopped)
    failure: str = ''                 # the breakdown's reason
    gap_level: int = OK               # WARN / ERROR after a bridged IMU gap, until re-converged
    gap_s: float = 0.0                # the last bridged gap, s
    recover_mark: int = 0             # NIS windows completed when the gap was bridged
    # the consistency ERROR's cause, kept as it was when it struck (the monitor's count and last
    # window move on; the ERROR persists): the failing windows in a row and the last of them
    inconsistent: tuple[int, WindowResult] | None = None

    def window_done(self, monitor: NisMonitor, failed: bool) -> None:
        """A NIS window completed: one that passed, entirely after the gap, ends the gap's level;
        the window that puts the monitor at ERROR is kept as the failure's reason."""
        if self.gap_level and not failed and monitor.completed > self.recover_mark:
            self.gap_level = OK
        if failed and self.inconsistent is None and monitor.level == ERROR and monitor.last is not None:
            self.inconsistent = (monitor.fails_in_row, monitor.last)


def level_and_flags(h: Health, monitor: NisMonitor) -> tuple[int, tuple[str, ...]]:
    """The level of the estimates and why (flags 'breakdown', 'inconsistent', 'gap')."""
    level, flags = OK, []
    if not h.running:
        level = ERROR
        flags.append('breakdown')
    if monitor.level:
        level = max(level, monitor.level)
        flags.append('inconsistent')
    if h.gap_level:
        level = max(level, h.gap_level)
        flags.append('gap')
    return level, tuple(flags)


def with_lag(level: int, flags: tuple[str, ...], lag_ns: int, bridge_ns: int, error_ns: int
             ) -> tuple[int, tuple[str, ...]]:
    """An output while the IMU has been silent for lag_ns (the gap not bridged yet): 'gap', WARN,
    ERROR beyond the gap limit (the slave solution is that old)."""
    if lag_ns <= bridge_ns:
        return level, flags
    return max(level, ERROR if lag_ns > error_ns else WARN), flags if 'gap' in flags else (*flags, 'gap')


def input_trouble(c: Counters, rejections: int) -> bool:
    """Any sample rejected (the rejections the stamps processed reached: input_streams.py), any
    IMU gap, any master sample unmatched, any LDV run not felt."""
    return bool(rejections + c.imu_gaps + c.unmatched_master + c.launch_not_felt)


def report(level: int, flags: tuple[str, ...], h: Health, monitor: NisMonitor, matching: bool,
           silent: tuple[str, ...], trouble: bool, relative_velocity: str) -> Report:
    """The /diagnostics status: the estimates' (level, flags), WARN for a silent master or LDV
    ('master_silent', 'ldv_silent') and for any input trouble so far, and its message."""
    if silent:
        level = max(level, WARN)
        flags += tuple(f'{k}_silent' for k in silent)
    if trouble:
        level = max(level, WARN)
    text = message(level, h, monitor, matching, silent)
    if relative_velocity != 'ldv':
        text += f'; relative velocity {relative_velocity}'
    return Report(level, flags, text)


def failure(h: Health, monitor: NisMonitor) -> str:
    """Why the estimate is not healthy ('' while it is)."""
    if not h.running:
        return h.failure
    if monitor.level == ERROR:
        # the windows that made it fail, not the monitor's count now (0 once a window passes)
        cause = h.inconsistent
        if cause is None and monitor.last is not None:      # a Health that saw no window (tests)
            cause = (monitor.fails_in_row, monitor.last)
        if cause is not None:
            n, r = cause
            return (f'inconsistent with its data: {n} NIS windows in a row above the bound '
                    f'(the last of them: mean {r.mean_per_dof:.3g} per dof, bound {r.bound / r.dof:.3g})')
    if h.gap_level == ERROR:
        return f'IMU gap of {h.gap_s:.3g} s: not re-converged yet'
    return ''


def message(level: int, h: Health, monitor: NisMonitor, matching: bool, silent: tuple[str, ...]) -> str:
    """One line for /diagnostics."""
    if not h.running:
        return f'numerical breakdown ({h.failure}): last good estimate held, filter stopped'
    why = failure(h, monitor)
    if level == ERROR and why:
        return f'{why}: last good estimate held'
    text = 'aligning' if matching else 'free inertial (no matching)'
    notes = []
    if h.gap_level:
        notes.append(f'IMU gap of {h.gap_s:.3g} s bridged')
    if monitor.level == WARN:
        notes.append('NIS window above its bound')
    if silent:
        notes.append(f"{', '.join(silent)} silent")
    return text + (f" ({'; '.join(notes)})" if notes else '')
