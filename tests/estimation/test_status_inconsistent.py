"""The consistency ERROR's message (estimation/status.py): it persists after a window passes, so
it must name the windows that made it fail, not the monitor's count now (the sweep's seed002,
master at 10 Hz, Butterworth lever arm at 0.505 Hz, 150 s: "0 NIS windows in a row above the
bound (last mean 1.28 per dof, bound 1.42)" from 91 s on)."""
from __future__ import annotations

from alignment_core.estimation import status
from alignment_core.estimation.consistency import NisMonitor
from alignment_core.estimation.health import ERROR

WINDOW = 10


def _window(h: status.Health, m: NisMonitor, nis: float) -> None:
    """One window of WINDOW 3-row updates of this NIS each, as the engine feeds them."""
    for _ in range(WINDOW):
        res = m.add(nis, 3)
        if res is not None:
            h.window_done(m, res.failed)


def _message(h: status.Health, m: NisMonitor) -> str:
    return status.report(*status.level_and_flags(h, m), h, m, True, (), False, 'ldv').message


def test_after_a_passing_window_the_message_names_the_windows_that_failed():
    h, m = status.Health(), NisMonitor(WINDOW, 1e-4, 3)
    for nis in (9.0, 8.4, 7.8):                 # 3.0, 2.8, 2.6 per dof: above the bound (2.25 per dof, D = 30)
        _window(h, m, nis)
    assert m.level == ERROR
    at_failure = status.failure(h, m)
    assert at_failure.startswith('inconsistent with its data: 3 NIS windows in a row')
    assert 'mean 2.6 per dof' in at_failure
    _window(h, m, 1.8)                          # 0.6 per dof: passes, the monitor's count is 0
    assert m.level == ERROR and m.fails_in_row == 0
    assert status.failure(h, m) == at_failure
    assert _message(h, m) == f'{at_failure}: last good estimate held'
    assert '0 NIS windows' not in _message(h, m) and '0.6 per dof' not in _message(h, m)


def test_windows_failing_after_the_error_do_not_change_its_reason():
    h, m = status.Health(), NisMonitor(WINDOW, 1e-4, 3)
    for nis in (9.0, 8.4, 7.8, 30.0, 1.8, 30.0):
        _window(h, m, nis)
    assert m.level == ERROR and m.fails_in_row == 1
    why = status.failure(h, m)
    assert '3 NIS windows in a row' in why and 'mean 2.6 per dof' in why and 'mean 10' not in why
