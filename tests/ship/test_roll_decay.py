"""Free roll decay of the MMG ship (no way, no wind, no rudder): from a 5 deg heel the roll
must oscillate at the damped natural period T_n / sqrt(1 - zeta^2) and decay with the
logarithmic decrement 2 pi zeta / sqrt(1 - zeta^2) of the configured zeta."""
import math

import numpy as np
import pytest

from alignment_core.ship.manoeuvring.mmg import SHIPS, MmgModel, rk4_step


@pytest.mark.parametrize('name', sorted(SHIPS))
def test_free_roll_decay_recovers_period_and_damping(name):
    ship = SHIPS[name]
    model = MmgModel(ship)
    h = ship.roll_period_s / 400.0
    y = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, math.radians(5.0), 0.0]
    phi = [y[6]]
    for _ in range(int(6 * ship.roll_period_s / h)):
        y, _ = rk4_step(lambda t, s: model.rhs(s, 0.0, 0.0), 0.0, y, h)
        phi.append(y[6])
    phi = np.array(phi)
    t = np.arange(len(phi)) * h
    # period from downward and upward zero crossings (linear interpolation)
    i = np.flatnonzero(np.sign(phi[:-1]) != np.sign(phi[1:]))
    tz = t[i] - phi[i] * h / (phi[i + 1] - phi[i])
    period = 2.0 * np.mean(np.diff(tz))
    zeta = ship.roll_zeta
    assert period == pytest.approx(ship.roll_period_s / math.sqrt(1.0 - zeta**2), rel=0.02)
    # damping from the logarithmic decrement of successive positive peaks
    pk = [phi[j] for j in range(1, len(phi) - 1) if phi[j] > phi[j - 1] and phi[j] >= phi[j + 1] and phi[j] > 0]
    delta = np.mean(np.log(np.array(pk[:-1]) / np.array(pk[1:])))
    assert delta / math.sqrt(4.0 * math.pi**2 + delta**2) == pytest.approx(zeta, rel=0.10)
