"""Flight segments after the release or from an airborne start (`aircraft.flight.*`): syntax,
parsing and checks."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from alignment_core.validation import keyed_items, require

SEGMENT_KINDS = ('level', 'climb', 'turn')
VERTICAL_KEYS = ('climb_rate_mps', 'flight_path_deg', 'pitch_deg')
TURN_KEYS = ('bank_deg', 'turn_rate_dps')
COMMON_KEYS = ('duration_s', 'speed_mps', 'transition_s', 'alpha_deg', 'beta_deg')
MAX_SPEED_MPS = 2500.0          # seed 004: Mach 7 at 20 km is 2066 m/s
MAX_ALPHA_DEG, MAX_BETA_DEG = 60.0, 30.0
ALLOWED_KEYS = {'level': COMMON_KEYS, 'climb': COMMON_KEYS + VERTICAL_KEYS,
                'turn': COMMON_KEYS + TURN_KEYS + VERTICAL_KEYS}


@dataclass(frozen=True)
class FlightSegment:
    """One parsed flight segment; None = not given (see the module docstring)."""
    kind: str
    duration_s: float = 0.0
    speed_mps: float | None = None
    transition_s: float | None = None
    climb_rate_mps: float | None = None
    flight_path_deg: float | None = None
    pitch_deg: float | None = None
    bank_deg: float | None = None
    turn_rate_dps: float | None = None
    alpha_deg: float | None = None
    beta_deg: float | None = None

    def given(self, keys: tuple[str, ...]) -> list[str]:
        return [k for k in keys if getattr(self, k) is not None]


def parse_segments(text: str) -> tuple[FlightSegment, ...]:
    """Parse and check a segment string; ConfigError names the segment and the problem."""
    items = keyed_items(text, 'segments', 'segment type', {k: ALLOWED_KEYS[k] for k in SEGMENT_KINDS})
    last = items[-1][0] if items else ''
    out = []
    for where, kind, vals in items:
        seg = FlightSegment(kind=kind, **vals)
        _check_segment(seg, where, last=(where == last))
        out.append(seg)
    return tuple(out)


def _check_segment(seg: FlightSegment, where: str, last: bool) -> None:
    require(seg.duration_s >= 0.0, f"{where}: duration_s must be >= 0, got {seg.duration_s}")
    require(seg.duration_s > 0.0 or last,
            f"{where}: duration_s must be > 0 (only the last segment may be open-ended, duration 0)")
    require(seg.duration_s <= 86400.0, f"{where}: duration_s must be <= 86400, got {seg.duration_s}")
    if seg.speed_mps is not None:
        require(1.0 <= seg.speed_mps <= MAX_SPEED_MPS,
                f"{where}: speed_mps must be in [1, {MAX_SPEED_MPS:g}], got {seg.speed_mps}")
    require(seg.alpha_deg is None or abs(seg.alpha_deg) <= MAX_ALPHA_DEG,
            f"{where}: alpha_deg must be within [-{MAX_ALPHA_DEG:g}, {MAX_ALPHA_DEG:g}], got {seg.alpha_deg}")
    require(seg.beta_deg is None or abs(seg.beta_deg) <= MAX_BETA_DEG,
            f"{where}: beta_deg must be within [-{MAX_BETA_DEG:g}, {MAX_BETA_DEG:g}], got {seg.beta_deg}")
    if seg.climb_rate_mps is not None and seg.speed_mps is not None:
        require(abs(seg.climb_rate_mps) < seg.speed_mps,
                f"{where}: |climb_rate_mps| must be below speed_mps, got {seg.climb_rate_mps} at {seg.speed_mps}")
    if seg.transition_s is not None:
        require(seg.transition_s > 0.0, f"{where}: transition_s must be > 0, got {seg.transition_s}")
    vert = seg.given(VERTICAL_KEYS)
    if seg.kind == 'climb':
        require(len(vert) == 1, f"{where}: a climb needs exactly one of {', '.join(VERTICAL_KEYS)}"
                                f"{' (got ' + ', '.join(vert) + ')' if vert else ''}")
    else:
        require(len(vert) <= 1, f"{where}: give at most one of {', '.join(VERTICAL_KEYS)}")
    for k in ('flight_path_deg', 'pitch_deg'):
        v = getattr(seg, k)
        require(v is None or abs(v) < 90.0, f"{where}: {k} must be within (-90, 90), got {v}")
    if seg.kind == 'turn':
        turn = seg.given(TURN_KEYS)
        require(len(turn) == 1, f"{where}: a turn needs exactly one of bank_deg, turn_rate_dps"
                                f"{' (got both)' if len(turn) == 2 else ''}")
        require(seg.bank_deg is None or abs(seg.bank_deg) < 90.0,
                f"{where}: bank_deg must be within (-90, 90), got {seg.bank_deg}")
        require(seg.turn_rate_dps is None or abs(seg.turn_rate_dps) <= 90.0,
                f"{where}: turn_rate_dps must be within [-90, 90], got {seg.turn_rate_dps}")


@dataclass(frozen=True)
class FlightConfig:
    """The flight. `segments` '' keeps the original free flight after the release (velocity
    and attitude held constant); otherwise a segment list (aircraft/flight.py).
    `transition_s`: default blend time of each segment's changes (roll-in/out, speed, climb,
    air angles); `settle_s`: time to rotate from the deck attitude into the flight attitude
    after the release; `alpha_deg`: initial angle of attack (body x above the velocity vector;
    sideslip starts at 0), which segments may change with `alpha_deg` / `beta_deg`.
    `start`: 'deck' (the flight begins at the catapult release) or 'airborne' (no deck phase,
    catapult disabled: the flight begins at the scenario start at the ship's origin latitude and
    longitude, at `start_height_m`, level at ground speed `start_speed_mps` along
    `start_track_deg`, ROS yaw: from East, counter-clockwise, north = 90; '' segments = level)."""
    segments: str = ''
    transition_s: float = 3.0
    settle_s: float = 2.0
    alpha_deg: float = 0.0
    start: Literal['deck', 'airborne'] = 'deck'
    start_height_m: float = 1000.0
    start_speed_mps: float = 60.0
    start_track_deg: float = 90.0

    def validate(self) -> None:
        require(0.0 < self.transition_s <= 60.0, f"transition_s must be in (0, 60], got {self.transition_s}")
        require(0.0 < self.settle_s <= 60.0, f"settle_s must be in (0, 60], got {self.settle_s}")
        require(abs(self.alpha_deg) <= MAX_ALPHA_DEG,
                f"alpha_deg must be within [-{MAX_ALPHA_DEG:g}, {MAX_ALPHA_DEG:g}], got {self.alpha_deg}")
        require(-500.0 <= self.start_height_m <= 100000.0,
                f"start_height_m must be in [-500, 100000], got {self.start_height_m}")
        require(1.0 <= self.start_speed_mps <= MAX_SPEED_MPS,
                f"start_speed_mps must be in [1, {MAX_SPEED_MPS:g}], got {self.start_speed_mps}")
        require(-360.0 <= self.start_track_deg <= 360.0,
                f"start_track_deg must be in [-360, 360], got {self.start_track_deg}")
        segs = parse_segments(self.segments)
        alpha = self.alpha_deg
        for i, s in enumerate(segs):
            where = f"segments[{i}] ({s.kind})"
            t = s.transition_s if s.transition_s is not None else self.transition_s
            require(s.duration_s == 0.0 or t <= s.duration_s + 1e-9,
                    f"{where}: the transition ({t} s) must fit in the segment's duration_s ({s.duration_s} s)")
            alpha = s.alpha_deg if s.alpha_deg is not None else alpha
            if s.pitch_deg is not None:
                require(abs(s.pitch_deg - alpha) < 90.0,
                        f"{where}: pitch_deg - alpha_deg must be within (-90, 90)")

    def parsed(self) -> tuple[FlightSegment, ...]:
        return parse_segments(self.segments)
