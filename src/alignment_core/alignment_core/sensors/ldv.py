"""Laser Doppler velocimeter (LDV): the aircraft's velocity relative to the deck, ship axes.

v_meas = (I + diag(k)) v_rel + b + n, n white (noise_mps), k and b random constants per axis
(1-sigma scale_ppm, bias_mps; stream stage_rng(seed, 'ldv_errors')). No measurement
(valid = False, published with covariance[0] = -1) when the aircraft is outside the beam
along the catapult track (at `track_heading_deg` from the bow), farther than max_range_m from
the LDV head, faster than max_speed_mps relative to the deck, or in a dropout. Dropouts: a two-state Markov process,
starts at rate dropout_rate_hz (per second of valid time), exponential durations of mean
dropout_mean_s; fraction of time in dropout p = r d / (1 + r d); stepped exactly between
samples (stream 'ldv_dropout', stationary start). Own rate and latency: sensors/timing.py.
Everything is off by default (today's numbers).

`mode: beam` (sensors/ldv_beam.py): the range rate along the line of sight from a head on the
deck to a reflector on the aircraft, s_meas = (1 + k) s + b + n (the first axis's k and b), with
the geometric blockage of that module on top of the validity above; the sample carries
s u (the velocity along the beam, ship axes) and the unit line of sight u (`LdvSample.beam`).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.geometry import earth
from alignment_core.geometry.rotations import cross, rotate_batch
from alignment_core.rng import stage_rng
from alignment_core.samples import AircraftTruth, LdvSample, ShipBatch, ShipSample
from alignment_core.sensors.ldv_beam import line_of_sight, visible
from alignment_core.sensors.timing import SensorTiming
from alignment_core.validation import require


@dataclass(frozen=True)
class LdvConfig:
    """Laser Doppler velocimeter (seed 000: 0.01 m/s). Its beam runs along the catapult track
    from `origin_m` (the aircraft's start spot, ship axes), in the direction `track_heading_deg`
    from the bow, clockwise (the aircraft's heading on deck, which the scenario gives it by
    default: u = (cos psi, -sin psi, 0) in ship FLU axes); it measures while the aircraft is
    within `track_length_m` along the track and `beam_halfwidth_m` across it.
    The LDV head sits `head_offset_m` along the track from `origin_m` (negative: behind)."""
    noise_mps: float = 0.01
    origin_m: tuple[float, float, float] = (40.0, -10.0, 15.0)
    track_heading_deg: float = 0.0
    track_length_m: float = 95.0
    beam_halfwidth_m: float = 2.0
    bias_mps: float = 0.0              # 1-sigma random constant per axis
    scale_ppm: float = 0.0             # 1-sigma random constant per axis
    head_offset_m: float = 0.0
    max_range_m: float = 0.0           # 0 = unlimited: distance from the head
    max_speed_mps: float = 0.0         # 0 = unlimited: relative speed
    dropout_rate_hz: float = 0.0       # 0 = no dropouts
    dropout_mean_s: float = 0.2
    rate_hz: float = 0.0               # 0 = the scenario rate; else a divisor of it
    latency_s: float = 0.0
    # the beam (mode: beam, sensors/ldv_beam.py); vector: all three components (today)
    mode: Literal['vector', 'beam'] = 'vector'
    mount_m: tuple[float, float, float] = (100.0, -6.0, 16.0)      # the head on the deck, ship axes
    reflector_m: tuple[float, float, float] = (0.0, 0.0, 0.0)      # on the aircraft, aircraft axes from the IMU
    reflector_axis: tuple[float, float, float] = (1.0, 0.0, 0.0)   # the reflector faces this way (aircraft axes)
    reflector_halfangle_deg: float = 45.0     # acceptance half-angle: beyond it the line is blocked
    min_range_m: float = 1.0                  # the head nearer than this: blocked

    def validate(self) -> None:
        require(0.0 < self.noise_mps <= 10.0, f"noise_mps must be in (0, 10], got {self.noise_mps}")
        require(self.track_length_m > 0.0, f"track_length_m must be > 0, got {self.track_length_m}")
        require(-180.0 <= self.track_heading_deg <= 180.0,
                f"track_heading_deg must be in [-180, 180], got {self.track_heading_deg}")
        require(self.beam_halfwidth_m > 0.0, f"beam_halfwidth_m must be > 0, got {self.beam_halfwidth_m}")
        require(0.0 <= self.bias_mps <= 10.0, f"bias_mps must be in [0, 10], got {self.bias_mps}")
        require(0.0 <= self.scale_ppm <= 1e5, f"scale_ppm must be in [0, 1e5], got {self.scale_ppm}")
        require(abs(self.head_offset_m) <= 1000.0, f"head_offset_m must be within +-1000 m, got {self.head_offset_m}")
        require(self.max_range_m >= 0.0, f"max_range_m must be >= 0 (0 = unlimited), got {self.max_range_m}")
        require(self.max_speed_mps >= 0.0, f"max_speed_mps must be >= 0 (0 = unlimited), got {self.max_speed_mps}")
        require(0.0 <= self.dropout_rate_hz <= 100.0,
                f"dropout_rate_hz must be in [0, 100], got {self.dropout_rate_hz}")
        require(0.0 < self.dropout_mean_s <= 3600.0,
                f"dropout_mean_s must be in (0, 3600], got {self.dropout_mean_s}")
        require(0.0 <= self.rate_hz <= 2000.0, f"rate_hz must be in [0, 2000], got {self.rate_hz}")
        require(0.0 <= self.latency_s <= 1.0, f"latency_s must be in [0, 1] s, got {self.latency_s}")
        self.validate_beam()

    def validate_beam(self) -> None:
        require(self.mode in ('vector', 'beam'), f"mode must be 'vector' or 'beam', got {self.mode!r}")
        require(float(np.linalg.norm(self.reflector_axis)) > 0.0, "reflector_axis must not be zero")
        require(0.0 < self.reflector_halfangle_deg <= 90.0,
                f"reflector_halfangle_deg must be in (0, 90], got {self.reflector_halfangle_deg}")
        require(0.0 < self.min_range_m <= 1000.0, f"min_range_m must be in (0, 1000], got {self.min_range_m}")
        for k in ('mount_m', 'reflector_m'):
            require(float(np.max(np.abs(getattr(self, k)))) <= 1000.0, f"{k} must be within +-1000 m per axis")


def dropout_transition(rate_hz: float, mean_s: float, h: float) -> tuple[float, float]:
    """Exact probabilities over h of (valid -> dropout, dropout -> valid) for the two-state
    Markov process with rates r (start) and 1/d (end)."""
    a, b = rate_hz, 1.0 / mean_s
    p = a / (a + b)
    e = 1.0 - np.exp(-(a + b) * h)
    return p * e, (1.0 - p) * e


class LdvModel:
    """Relative velocity of the aircraft w.r.t. the deck, from ship and aircraft truth."""

    def __init__(self, cfg: LdvConfig, seed: int, plane: earth.TangentPlane) -> None:
        self.cfg = cfg
        self.rng = stage_rng(seed, 'ldv')
        self.plane = plane
        self.bias = np.zeros(3)
        self.scale = np.zeros(3)
        self.has_errors = cfg.bias_mps > 0.0 or cfg.scale_ppm > 0.0
        if self.has_errors:
            r = stage_rng(seed, 'ldv_errors')
            self.bias = r.standard_normal(3) * cfg.bias_mps
            self.scale = r.standard_normal(3) * cfg.scale_ppm * 1e-6
        psi = cfg.track_heading_deg * np.pi / 180.0
        self.track = np.array([np.cos(psi), -np.sin(psi), 0.0]) if psi != 0.0 else np.array([1.0, 0.0, 0.0])
        self.head = np.asarray(cfg.origin_m, dtype=float) + cfg.head_offset_m * self.track
        self.dropouts = cfg.dropout_rate_hz > 0.0
        if self.dropouts:
            self.drop_rng = stage_rng(seed, 'ldv_dropout')
            self.in_dropout: bool | None = None
            self.last_t: int | None = None

    def measure(self, s: ShipSample, a: AircraftTruth) -> LdvSample:
        return self.measure_batch(ShipBatch.of([s]), a.p_w[None], a.q_nb[None], a.v_b[None], a.w_b[None])[0]

    def _dropout_batch(self, t_ns: np.ndarray) -> np.ndarray:
        """True where the LDV is in a dropout (K,); stepped sample by sample."""
        cfg = self.cfg
        u = self.drop_rng.random(len(t_ns))
        out = np.empty(len(t_ns), dtype=bool)
        for k, t in enumerate(t_ns):
            if self.in_dropout is None or self.last_t is None:     # the first sample: both unset
                p = cfg.dropout_rate_hz * cfg.dropout_mean_s
                self.in_dropout = bool(u[k] < p / (1.0 + p))
            else:
                start, end = dropout_transition(cfg.dropout_rate_hz, cfg.dropout_mean_s,
                                                (int(t) - self.last_t) * 1e-9)
                self.in_dropout = bool(u[k] >= end) if self.in_dropout else bool(u[k] < start)
            self.last_t = int(t)
            out[k] = self.in_dropout
        return out

    def measure_batch(self, sb: ShipBatch, p_a: np.ndarray, q_a: np.ndarray, v_a_b: np.ndarray,
                      w_a_b: np.ndarray | None = None) -> list[LdvSample]:
        """K measurements from ship samples and aircraft truth (positions, attitudes, body
        velocities, body rates w.r.t. nav (beam mode; None: rigid on the ship), each (K, ...))."""
        cfg = self.cfg
        if cfg.mode == 'beam':
            return self._beam_batch(sb, p_a, q_a, v_a_b, w_a_b)
        n = self.rng.standard_normal((len(sb), 3)) * cfg.noise_mps
        c_lw = np.swapaxes(self.plane.c_local_to_world(sb.p_w), -1, -2)  # world -> local ENU
        r = rotate_batch(sb.q_nb, np.einsum('kij,kj->ki', c_lw, p_a - sb.p_w), inverse=True)   # C_n^s
        d = r - np.asarray(cfg.origin_m)
        if cfg.track_heading_deg == 0.0:
            along, across = d[:, 0], np.hypot(d[:, 1], d[:, 2])
        else:
            along = np.einsum('ki,i->k', d, self.track)
            across = np.linalg.norm(d - along[:, None] * self.track, axis=1)
        valid = (along >= -cfg.beam_halfwidth_m) & (along <= cfg.track_length_m) & (across <= cfg.beam_halfwidth_m)
        v_a_n = rotate_batch(q_a, v_a_b)
        v_s_n = rotate_batch(sb.q_nb, sb.v_b)
        v_true = rotate_batch(sb.q_nb, v_a_n - v_s_n, inverse=True) - cross(sb.w_b, r)
        if cfg.max_range_m > 0.0:
            valid &= np.linalg.norm(r - self.head, axis=1) <= cfg.max_range_m
        if cfg.max_speed_mps > 0.0:
            valid &= np.linalg.norm(v_true, axis=1) <= cfg.max_speed_mps
        if self.dropouts:
            valid &= ~self._dropout_batch(sb.t_ns)
        if self.has_errors:
            v_true = v_true * (1.0 + self.scale) + self.bias
        return _samples(sb.t_ns, v_true + n, valid, cfg.noise_mps)

    def _relative(self, sb: ShipBatch, p_a: np.ndarray, q_a: np.ndarray, v_a_b: np.ndarray
                  ) -> tuple[Rotation, np.ndarray, np.ndarray, np.ndarray]:
        """(C_n^s, IMU spots r (K, 3), their velocities relative to the deck (K, 3), validity on
        the track (K,)), ship axes."""
        cfg = self.cfg
        c_ns = Rotation.from_quat(sb.q_nb).inv()
        c_lw = np.swapaxes(self.plane.c_local_to_world(sb.p_w), -1, -2)
        r = rotate_batch(sb.q_nb, np.einsum('kij,kj->ki', c_lw, p_a - sb.p_w), inverse=True)
        d = r - np.asarray(cfg.origin_m)
        along = np.einsum('ki,i->k', d, self.track)
        across = np.linalg.norm(d - along[:, None] * self.track, axis=1)
        valid = (along >= -cfg.beam_halfwidth_m) & (along <= cfg.track_length_m) & (across <= cfg.beam_halfwidth_m)
        v_rel = rotate_batch(sb.q_nb, rotate_batch(q_a, v_a_b) - rotate_batch(sb.q_nb, sb.v_b), inverse=True) \
            - cross(sb.w_b, r)
        if cfg.max_range_m > 0.0:
            valid &= np.linalg.norm(r - self.head, axis=1) <= cfg.max_range_m
        return c_ns, r, v_rel, valid

    def _beam_batch(self, sb: ShipBatch, p_a: np.ndarray, q_a: np.ndarray, v_a_b: np.ndarray,
                    w_a_b: np.ndarray | None) -> list[LdvSample]:
        """Beam mode (module docstring, sensors/ldv_beam.py)."""
        cfg = self.cfg
        n = self.rng.standard_normal(len(sb)) * cfg.noise_mps
        c_ns, r, v_rel, valid = self._relative(sb, p_a, q_a, v_a_b)
        u, rng, s, c_as = line_of_sight(c_ns, q_a, r, v_rel, sb.w_b, w_a_b, np.asarray(cfg.mount_m, dtype=float),
                                        np.asarray(cfg.reflector_m, dtype=float))
        valid &= visible(u, rng, c_as, np.asarray(cfg.reflector_axis, dtype=float),
                         cfg.reflector_halfangle_deg * np.pi / 180.0, cfg.min_range_m)
        if cfg.max_speed_mps > 0.0:
            valid &= np.abs(s) <= cfg.max_speed_mps
        if self.dropouts:
            valid &= ~self._dropout_batch(sb.t_ns)
        if self.has_errors:
            s = s * (1.0 + self.scale[0]) + self.bias[0]
        s = s + n
        return _samples(sb.t_ns, s[:, None] * u, valid, cfg.noise_mps, u)


def _samples(t_ns: np.ndarray, v_s: np.ndarray, valid: np.ndarray, sigma: float,
             beam: np.ndarray | None = None) -> list[LdvSample]:
    """The samples of K rows: stamps t_ns, velocities v_s (K, 3), validity, beams (K, 3) or None;
    an invalid sample carries a zero velocity and no beam."""
    zero = np.zeros(3)
    beams = beam if beam is not None else [None] * len(v_s)
    return [LdvSample(t, v if ok else zero, sigma, ok, b if ok else None)
            for t, v, ok, b in zip(t_ns.tolist(), v_s, valid.tolist(), beams)]


class LdvStage:
    """Ship samples + aircraft truth in -> LDV samples at its rate, stamped t + latency and
    released when simulation time reaches the stamp (node: `step`; batch: `run_batch`)."""

    def __init__(self, cfg: LdvConfig, seed: int, plane: earth.TangentPlane, base_rate_hz: float,
                 t0_ns: int) -> None:
        self.model = LdvModel(cfg, seed, plane)
        self.timing = SensorTiming(cfg.rate_hz, cfg.latency_s, base_rate_hz, t0_ns)

    def _stamped(self, samples: list[LdvSample]) -> list[LdvSample]:
        lat = self.timing.latency_ns
        if not lat:
            return samples
        return [LdvSample(t_ns=s.t_ns + lat, v_s=s.v_s, sigma=s.sigma, valid=s.valid, beam=s.beam) for s in samples]

    def step(self, s: ShipSample, a: AircraftTruth) -> list[LdvSample]:
        new = self._stamped([self.model.measure(s, a)]) if self.timing.due(s.t_ns) else []
        return self.timing.release(s.t_ns, new)

    def step_many(self, ships: Sequence[ShipSample], aircraft: Sequence[AircraftTruth]) -> list[LdvSample]:
        """`step` on each of K (ship, aircraft) pairs in turn, as one batched call: the same
        samples, bit for bit, and the same state afterwards (noise stream, dropouts, pending
        releases); what `step` releases on the way comes out at the last pair's time."""
        if not ships:
            return []
        sb = ShipBatch.of(list(ships))
        idx = np.flatnonzero(self.timing.due_mask(sb.t_ns))
        new: list[LdvSample] = []
        if len(idx):
            sel = [aircraft[int(i)] for i in idx]
            new = self._stamped(self.model.measure_batch(
                sb.slice(idx), np.array([a.p_w for a in sel]), np.array([a.q_nb for a in sel]),
                np.array([a.v_b for a in sel]), np.array([a.w_b for a in sel])))
        return self.timing.release(int(sb.t_ns[-1]), new)

    def run_batch(self, sb: ShipBatch, p_a: np.ndarray, q_a: np.ndarray, v_a_b: np.ndarray,
                  w_a_b: np.ndarray | None = None) -> list[LdvSample]:
        idx = np.flatnonzero(self.timing.due_mask(sb.t_ns))
        w = None if w_a_b is None else w_a_b[idx]
        out = self.model.measure_batch(sb.slice(idx), p_a[idx], q_a[idx], v_a_b[idx], w) if len(idx) else []
        return self.timing.release_batch(self._stamped(out), int(sb.t_ns[-1]))
