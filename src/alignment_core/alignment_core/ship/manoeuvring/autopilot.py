"""Rudder commands for the MMG ship: a course-keeping PID autopilot with a course/speed
schedule, the steering gear (angle and rate limits), and the standard trial manoeuvres
(turning circle, zig-zag).

Signs follow `mmg`: heading psi from North clockwise, rudder delta > 0 turns to starboard,
so the autopilot commands delta_c = kp e + ki int(e) - kd (r - psi_d'), e = psi_d - psi.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


def wrap(a: float) -> float:
    """Angle to (-pi, pi]."""
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


@dataclass(frozen=True)
class SteeringGear:
    """Rudder servo: delta' = clip(gain (clip(delta_c) - delta), +-rate); angles in rad,
    rate in rad/s, gain in 1/s (the rudder moves at its rate limit until it is within
    rate/gain of the order)."""
    max_angle: float
    rate: float
    gain: float = 2.0

    def rate_of(self, delta: float, command: float) -> float:
        c = min(max(command, -self.max_angle), self.max_angle)
        return min(max(self.gain * (c - delta), -self.rate), self.rate)


@dataclass(frozen=True)
class Autopilot:
    """Course-keeping PID: kp (rad of rudder per rad of heading error), ki (1/s), kd (s);
    the integral only runs within `band` (rad) of the ordered heading and stops while the
    command is saturated (anti-windup: a large course change does not wind it up)."""
    kp: float
    ki: float
    kd: float
    max_angle: float
    band: float = math.radians(5.0)

    def command(self, err: float, r_err: float, integral: float) -> tuple[float, float]:
        """(rudder order, d/dt of the integral) for heading error `err` (rad), yaw-rate error
        r - psi_d' (rad/s) and the integral state."""
        raw = self.kp * err + self.ki * integral - self.kd * r_err
        sat = min(max(raw, -self.max_angle), self.max_angle)
        grow = err if (abs(err) < self.band and (sat == raw or raw * err < 0.0)) else 0.0
        return sat, grow


@dataclass(frozen=True)
class CourseSchedule:
    """Ordered heading and speed: `heading0` (rad) and `speed0` (m/s) until `turn_at` (s;
    negative: never), then `turn_to` (rad; the shorter way round), reached at `turn_rate`
    (rad/s; 0: ordered at once), and `speed_to` (m/s; negative: unchanged)."""
    heading0: float
    speed0: float
    turn_at: float = -1.0
    turn_to: float = 0.0
    turn_rate: float = 0.0
    speed_to: float = -1.0

    @property
    def turning(self) -> bool:
        return self.turn_at >= 0.0

    @property
    def final_heading(self) -> float:
        """Unwrapped ordered heading after the turn (rad)."""
        if not self.turning:
            return self.heading0
        return self.heading0 + wrap(self.turn_to - self.heading0)

    def heading(self, t: float) -> tuple[float, float]:
        """Ordered heading (unwrapped, rad) and its rate (rad/s) at time t."""
        if not self.turning or t < self.turn_at:
            return self.heading0, 0.0
        d = self.final_heading - self.heading0
        if self.turn_rate <= 0.0:
            return self.final_heading, 0.0
        done = self.turn_rate * (t - self.turn_at)
        if done >= abs(d):
            return self.final_heading, 0.0
        return self.heading0 + math.copysign(done, d), math.copysign(self.turn_rate, d)

    def speed(self, t: float) -> float:
        if self.turning and self.speed_to >= 0.0 and t >= self.turn_at:
            return self.speed_to
        return self.speed0


class ZigZag:
    """Zig-zag trial order (e.g. 10/10): `angle` to starboard first, reversed each time the
    heading passes `deviation` beyond the initial heading `psi0` (rad). Stateful: call once
    per time step with the current heading."""

    def __init__(self, angle: float, deviation: float, psi0: float, first: float = 1.0) -> None:
        self.angle, self.dev, self.psi0 = angle, deviation, psi0
        self.sign = 1.0 if first >= 0.0 else -1.0

    def __call__(self, psi: float) -> float:
        dpsi = psi - self.psi0
        if self.sign > 0.0 and dpsi >= self.dev:
            self.sign = -1.0
        elif self.sign < 0.0 and dpsi <= -self.dev:
            self.sign = 1.0
        return self.sign * self.angle
