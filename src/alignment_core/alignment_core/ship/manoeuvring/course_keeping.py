"""Low-frequency ship track from the MMG model steered by the autopilot (`course_keeping:
mmg`): integrated once by RK4 on a fixed grid from t = 0 and represented by an interpolant
whose derivatives are exact, so that position, velocity, acceleration, heading, yaw rate and
roll are mutually consistent to INS grade.

Closed loop (state [N, E, psi, u, v, r, phi, p, delta, n, int e]): `mmg.MmgModel` with the
rudder angle delta from `autopilot.SteeringGear` following `autopilot.Autopilot`, which
steers to `autopilot.CourseSchedule`; propeller revs n follow the calm-water equilibrium
revs of the ordered speed with a first-order lag (`SHAFT_LAG_S`); optional external forces
(`box_ship_waves.BoxShipWaves`) and steady wind (`mmg.Wind`). The loop first runs
`WARMUP_S` seconds before t = 0 (autopilot and wind transients settle), the track's
position is then taken relative to its value at t = 0.

Interpolant: on each step [t_k, t_k + h] a quintic Hermite polynomial per channel (north,
east, heading, roll) matching value, first and second derivative at both knots (taken from
the ODE's right-hand side): C2 across knots, so acceleration, yaw acceleration and roll
acceleration are continuous and exactly the derivatives of the positions and angles.

Geodesy: the north distance is the meridian arc from the start latitude (Helmert's series in
the third flattening, inverted by Newton), so lat' = v_N / R_M exactly; the longitude is
lon0 + int v_E / (R_N cos lat) dt, by 8-point Gauss-Legendre on each step (and on the part
step up to t), so lon' = v_E / (R_N cos lat). Heights are zero (heave is wave frequency).

The grid extends lazily (blocks of `BLOCK` steps) as later times are asked for: any chunking
of the evaluation gives the same numbers. Only the recent steps are kept (KEEP before the least
time read), so a node's track holds a bounded history however long it runs. The tracks of one
configuration may share their start (`SharedStart`: the warm-up and the first blocks, integrated
once) and their kinematics at times asked for before: a Monte Carlo's runs differ in their sea,
never in their track.
"""
from __future__ import annotations

import math
import threading
from collections import OrderedDict

import numpy as np

from alignment_core.geometry import earth
from alignment_core.recent_rows import RecentRows
from alignment_core.ship.manoeuvring.autopilot import Autopilot, CourseSchedule, SteeringGear
from alignment_core.ship.manoeuvring.mmg import I_E, I_N, I_P, I_PHI, I_PSI, I_R, I_U, I_V, MmgModel, rk4_step

WARMUP_S = 600.0
SHAFT_LAG_S = 20.0
BLOCK = 1024
KEEP = 2 * BLOCK
"""Grid steps before the least time of a read that stay readable (recent_rows.py): far more than
the spectral motion's knot blocks (25.6 s) reach back before the times a node asks for."""

SHARED_BLOCKS = 8
"""Blocks of a track's start (68 min at 0.5 s steps) that the tracks of a configuration share."""

SHARED_KINEMATICS_BYTES = 32 * 2**20
"""The kinematics the tracks of a configuration share, at most (their times and arrays): a 300 s
run at 100 Hz asks for about 4 MB."""
ASKED_KEPT = 4096
"""Times asked for once that a configuration remembers (by hash) until they are asked again."""

_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_GL_U = 0.5 * (_GL_X + 1.0)                   # nodes on [0, 1]
_GL_WU = 0.5 * _GL_W
_N3 = earth.F / (2.0 - earth.F)               # third flattening
_ARC = earth.A / (1.0 + _N3) * np.array([
    1.0 + _N3**2 / 4.0 + _N3**4 / 64.0,
    -1.5 * (_N3 - _N3**3 / 8.0),
    15.0 / 16.0 * (_N3**2 - _N3**4 / 4.0),
    -35.0 / 48.0 * _N3**3,
    315.0 / 512.0 * _N3**4])


def meridian_arc(lat):
    """Meridian arc length from the equator to `lat` (m), Helmert's series (error ~1e-14)."""
    lat = np.asarray(lat, dtype=float)
    c = _ARC
    return (c[0] * lat + c[1] * np.sin(2 * lat) + c[2] * np.sin(4 * lat) + c[3] * np.sin(6 * lat)
            + c[4] * np.sin(8 * lat))


def lat_of_north(north, lat0: float, arc0: float | None = None):
    """Latitude (rad) at `north` metres of meridian arc from `lat0`."""
    north = np.asarray(north, dtype=float)
    arc0 = float(meridian_arc(lat0)) if arc0 is None else arc0
    r_m0, _ = earth.radii(lat0)
    lat = lat0 + north / r_m0
    for _ in range(3):
        r_m, _ = earth.radii(lat)
        lat = lat - (meridian_arc(lat) - arc0 - north) / r_m
    return lat


def quintic_coefficients(y0, d0, a0, y1, d1, a1, h):
    """Coefficients c0..c5 (last axis) of the quintic in s = (t - t0)/h with the given value,
    first and second time derivatives at both ends."""
    c0, c1, c2 = y0, h * d0, 0.5 * h * h * a0
    dl = y1 - (c0 + c1 + c2)
    d1s = h * d1 - (c1 + 2.0 * c2)
    d2s = h * h * a1 - 2.0 * c2
    c3 = 10.0 * dl - 4.0 * d1s + 0.5 * d2s
    c4 = -15.0 * dl + 7.0 * d1s - d2s
    c5 = 6.0 * dl - 3.0 * d1s + 0.5 * d2s
    return np.stack([c0, c1, c2, c3, c4, c5], axis=-1)


def quintic_values(c, s, h, order: int = 2):
    """Value and time derivatives up to `order` of quintics c (..., 6) at s (broadcast)."""
    out = []
    p = c[..., 5]
    for j in (4, 3, 2, 1, 0):
        p = p * s + c[..., j]
    out.append(p)
    if order >= 1:
        q = 5.0 * c[..., 5]
        for j in (4, 3, 2, 1):
            q = q * s + j * c[..., j]
        out.append(q / h)
    if order >= 2:
        w = 20.0 * c[..., 5]
        for j in (4, 3, 2):
            w = w * s + j * (j - 1) * c[..., j]
        out.append(w / (h * h))
    return out


class SharedStart:
    """The integrated start of a track: the state after the warm-up and its offset, then per
    block of the grid (the first SHARED_BLOCKS) the state and derivative at its last knot, its
    quintic coefficients (BLOCK, 24) and longitudes at its knots (BLOCK, 1). A track replays what
    an earlier one stored: the same numbers, bit for bit (they are that one's), without
    integrating them again. Tracks store only once a second one has been made (`users`): a
    process with one track (a node) keeps no copy, which would grow its memory block by block.
    Only tracks of one configuration, without external forces, may share one (`make_track`
    keeps one per configuration)."""

    def __init__(self) -> None:
        self.users = 0                                # tracks made with it
        self.warm: tuple[tuple[float, ...], tuple[float, float]] | None = None
        self.blocks: list[tuple[tuple[float, ...], tuple[float, ...], np.ndarray, np.ndarray]] = []
        self.kinematics: OrderedDict[bytes, dict[str, np.ndarray]] = OrderedDict()   # by the times' bytes
        self._kinematics_bytes = 0
        self._asked: set[int] = set()                 # hashes of the times asked for once, not stored
        self._lock = threading.Lock()

    def recall_kinematics(self, key: bytes) -> dict[str, np.ndarray] | None:
        """Copies of the kinematics stored at the times whose float64 bytes are `key`, or None."""
        with self._lock:
            kin = self.kinematics.get(key)
            return None if kin is None else {k: a.copy() for k, a in kin.items()}

    def store_kinematics(self, key: bytes, kin: dict[str, np.ndarray]) -> None:
        """Keep a copy of a track's kinematics at the times `key` once they have been asked for
        before (a Monte Carlo's runs ask again; a stepped run's chunks never do), if another track
        may ask for them; the oldest go beyond SHARED_KINEMATICS_BYTES."""
        size = len(key) + sum(a.nbytes for a in kin.values())
        with self._lock:
            if self.users < 2 or key in self.kinematics or size > SHARED_KINEMATICS_BYTES:
                return
            seen = hash(key)
            if seen not in self._asked:
                if len(self._asked) >= ASKED_KEPT:
                    self._asked.clear()
                self._asked.add(seen)
                return
            self._asked.discard(seen)
            self.kinematics[key] = {k: a.copy() for k, a in kin.items()}
            self._kinematics_bytes += size
            while self._kinematics_bytes > SHARED_KINEMATICS_BYTES:
                old_key, old = self.kinematics.popitem(last=False)
                self._kinematics_bytes -= len(old_key) + sum(a.nbytes for a in old.values())

    def store_warm(self, y: list[float], offset: tuple[float, float]) -> None:
        """Keep the state after the warm-up and its offset, if another track may replay them."""
        with self._lock:
            if self.users > 1 and self.warm is None:
                self.warm = (tuple(y), offset)

    def store_block(self, block: int, y: list[float], f: list[float], coef_rows: np.ndarray,
                    lon_rows: np.ndarray) -> None:
        """Keep a copy of a block's result (its last knot's state and derivative, coefficients
        and longitudes) if it is the next one, within SHARED_BLOCKS, and another track may
        replay it."""
        with self._lock:
            if self.users > 1 and block == len(self.blocks) < SHARED_BLOCKS:
                self.blocks.append((tuple(y), tuple(f), coef_rows.copy(), lon_rows.copy()))


class ManoeuvringTrack:
    """The closed-loop MMG track (module docstring). `kinematics(t)` gives the arrays the
    ship truth needs; `states` (knots x 11) the raw RK4 states on the grid."""

    N_STATE = 11
    I_DELTA, I_REVS, I_INT = 8, 9, 10

    def __init__(self, model: MmgModel, autopilot: Autopilot, gear: SteeringGear,
                 schedule: CourseSchedule, lat0: float, lon0: float, step: float,
                 external=None, warmup: float = WARMUP_S, shared: SharedStart | None = None) -> None:
        """shared: the start of tracks of this same configuration: what it holds is replayed,
        what it lacks stored once there is a second track (SharedStart)."""
        self.model, self.ap, self.gear, self.sched = model, autopilot, gear, schedule
        self._shared = shared
        if shared is not None:
            shared.users += 1
        self.ext = external
        self.lat0, self.lon0, self.h = lat0, lon0, step
        self.arc0 = float(meridian_arc(lat0))
        self._revs: dict[float, float] = {}
        u0 = schedule.speed0
        y = [0.0] * self.N_STATE
        # start the warm-up where a straight run would put t = 0 at the origin
        y[I_N] = -u0 * warmup * math.cos(schedule.heading0)
        y[I_E] = -u0 * warmup * math.sin(schedule.heading0)
        y[I_PSI], y[I_U], y[self.I_REVS] = schedule.heading0, u0, self._revs_for(u0)
        if shared is not None and shared.warm is not None:
            y, self.offset = list(shared.warm[0]), shared.warm[1]
        else:
            n_warm = int(round(warmup / step))
            for k in range(n_warm):
                y, _ = rk4_step(self.rhs, -warmup + k * step, y, step)
            self.offset = (y[I_N], y[I_E])
            if shared is not None:
                shared.store_warm(y, self.offset)
        self._y = y                                   # state at the last knot
        self._f = self.rhs(0.0, y)                    # its derivative
        self._steps = 0                               # grid steps integrated (knots 0 .. steps)
        room = 2 * (KEEP + 2 * BLOCK)                 # twice the most a forward run holds: no growth later
        self._coef = RecentRows(4 * 6, room)          # quintic coefficients (4, 6) per step
        self._lon_knots = RecentRows(1, room)         # longitude at each knot
        self._lon_knots.append(np.array([lon0]))

    def _revs_for(self, speed: float) -> float:
        if speed not in self._revs:
            self._revs[speed] = self.model.equilibrium_revs(speed)
        return self._revs[speed]

    def rhs(self, t: float, y: list[float]) -> list[float]:
        psi_d, psi_d_dot = self.sched.heading(t)
        delta_c, d_int = self.ap.command(psi_d - y[I_PSI], y[I_R] - psi_d_dot, y[self.I_INT])
        d_delta = self.gear.rate_of(y[self.I_DELTA], delta_c)
        d_revs = (self._revs_for(self.sched.speed(t)) - y[self.I_REVS]) / SHAFT_LAG_S
        ext = (0.0, 0.0, 0.0, 0.0)
        if self.ext is not None:
            ext = self.ext(t, y[I_N], y[I_E], y[I_PSI])
        d = self.model.rhs(y, y[self.I_DELTA], y[self.I_REVS], ext)
        return d + [d_delta, d_revs, d_int]

    # --- grid --------------------------------------------------------------------------------
    @property
    def t_end(self) -> float:
        return self._steps * self.h

    def _extend(self, n: int) -> None:
        h, k0 = self.h, self._steps
        block = k0 // BLOCK if n == BLOCK and k0 % BLOCK == 0 else SHARED_BLOCKS
        sh = self._shared
        if sh is not None and block < len(sh.blocks):           # integrated by a track before this one
            y_end, f_end, coef_rows, lon_rows = sh.blocks[block]
            self._y, self._f = list(y_end), list(f_end)
            self._steps += n
            self._coef.extend(coef_rows)
            self._lon_knots.extend(lon_rows)
            return
        ys, fs = [], []
        y, f = self._y, self._f
        prev_y, prev_f = np.array(y, dtype=float), np.array(f, dtype=float)
        for k in range(n):
            y, _ = rk4_step(self.rhs, (k0 + k) * h, y, h)
            f = self.rhs((k0 + k + 1) * h, y)
            ys.append(y)
            fs.append(f)
        self._y, self._f = y, f
        self._steps += n
        y0 = np.vstack([prev_y, ys[:-1]]) if n > 1 else prev_y[None]
        f0 = np.vstack([prev_f, fs[:-1]]) if n > 1 else prev_f[None]
        y1, f1 = np.asarray(ys), np.asarray(fs)
        ch0, ch1 = self._channels(y0, f0), self._channels(y1, f1)
        coef = quintic_coefficients(*ch0, *ch1, h)     # (n, 4, 6)
        coef_rows = coef.reshape(n, 4 * 6)
        self._coef.extend(coef_rows)
        # longitude at the new knots
        nodes = _GL_U[None, :]
        north = quintic_values(coef[:, None, 0], nodes, h, 0)[0]
        e_dot = quintic_values(coef[:, None, 1], nodes, h, 1)[1]
        q = self._q(north)
        inc = h * np.sum(q * e_dot * _GL_WU, axis=1)
        lon_rows = (self._lon_knots[self._lon_knots.n - 1][0] + np.cumsum(inc))[:, None]
        self._lon_knots.extend(lon_rows)
        if sh is not None:
            sh.store_block(block, y, f, coef_rows, lon_rows)

    def _channels(self, y: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(value, first, second derivative), each (n, 4), of north, east, psi, phi (north
        and east relative to the t = 0 position)."""
        psi, u, v, r = y[:, I_PSI], y[:, I_U], y[:, I_V], y[:, I_R]
        du, dv, dr, dp = f[:, I_U], f[:, I_V], f[:, I_R], f[:, I_P]
        c, s = np.cos(psi), np.sin(psi)
        val = np.stack([y[:, I_N] - self.offset[0], y[:, I_E] - self.offset[1], psi, y[:, I_PHI]], -1)
        d1 = np.stack([f[:, I_N], f[:, I_E], r, y[:, I_P]], -1)
        a_n = du * c - u * r * s - dv * s - v * r * c
        a_e = du * s + u * r * c + dv * c - v * r * s
        d2 = np.stack([a_n, a_e, dr, dp], -1)
        return val, d1, d2

    def _q(self, north):
        """1 / (R_N cos lat) at `north` metres from the start."""
        lat = lat_of_north(north, self.lat0, self.arc0)
        _, r_n = earth.radii(lat)
        return 1.0 / (r_n * np.cos(lat))

    def _ensure(self, t_max: float) -> None:
        while self.t_end <= t_max:
            self._extend(BLOCK)

    # --- evaluation ----------------------------------------------------------------------------
    def kinematics(self, t) -> dict[str, np.ndarray]:
        """At times t (s, >= 0): 'north', 'east' (m from the start), 'v_n', 'a_n' (ENU,
        (N, 3)), 'psi', 'psi_dot', 'psi_ddot' (heading from North clockwise), 'phi',
        'phi_dot', 'phi_ddot' (roll, starboard down), 'lat', 'lon' (rad)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        shared, key = self._shared, b''
        if shared is not None:                       # another track of the configuration may have them
            key = t.tobytes()
            recalled = shared.recall_kinematics(key)
            if recalled is not None:
                return recalled
        if len(t):
            self._ensure(float(np.max(t)))
        h = self.h
        idx = np.clip(np.floor(t / h).astype(np.int64), 0, self._coef.n - 1)
        s = t / h - idx
        c = self._coef[idx].reshape(-1, 4, 6)                        # (N, 4, 6)
        val, d1, d2 = quintic_values(c, s[:, None], h, 2)
        north, east = val[:, 0], val[:, 1]
        lat = lat_of_north(north, self.lat0, self.arc0)
        # longitude: knot value plus the part step, Gauss-Legendre on [t_k, t]
        nodes = s[:, None] * _GL_U[None, :]                          # (N, 8)
        n_nodes = quintic_values(c[:, None, 0], nodes, h, 0)[0]
        ed_nodes = quintic_values(c[:, None, 1], nodes, h, 1)[1]
        part = h * s * np.sum(self._q(n_nodes) * ed_nodes * _GL_WU, axis=1)
        lon = self._lon_knots[idx][:, 0] + part
        if len(idx):                        # a node's reads move forward; a batch reads all at once
            self._coef.forget_before(int(idx.min()) - KEEP)
            self._lon_knots.forget_before(int(idx.min()) - KEEP)
        n = len(t)
        v_n = np.zeros((n, 3))
        a_n = np.zeros((n, 3))
        v_n[:, 0], v_n[:, 1] = d1[:, 1], d1[:, 0]
        a_n[:, 0], a_n[:, 1] = d2[:, 1], d2[:, 0]
        kin = {'north': north, 'east': east, 'v_n': v_n, 'a_n': a_n,
               'psi': val[:, 2], 'psi_dot': d1[:, 2], 'psi_ddot': d2[:, 2],
               'phi': val[:, 3], 'phi_dot': d1[:, 3], 'phi_ddot': d2[:, 3],
               'lat': lat, 'lon': lon}
        if shared is not None:
            shared.store_kinematics(key, kin)
        return kin

