"""The batch pipeline: the graph's stages wired in-process, in the same order and with the
same records the nodes exchange, so both give the same numbers for a scenario and seed."""
from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from alignment_core.aircraft.kinematics import AircraftKinematics
from alignment_core.config.scenario import Scenario, tau_of
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.outputs import Estimate
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import relative_rotvec_batch
from alignment_core.samples import (
    AircraftTruth,
    DopplerSample,
    ImuSample,
    LdvSample,
    MasterSample,
    ShipBatch,
    ShipSample,
)
from alignment_core.sensors import ldv_wire
from alignment_core.sensors.doppler_radar import DopplerStage
from alignment_core.sensors.imu import ImuErrorModel
from alignment_core.sensors.ldv import LdvStage
from alignment_core.sensors.master_ins import MasterInsStage
from alignment_core.ship.motion import make_motion
from alignment_core.ship.paper import PaperShipMotion
from alignment_core.ship.stamped import split
from alignment_core.units import DEG


def plane_of(sc: Scenario) -> earth.TangentPlane:
    return earth.TangentPlane(sc.ship.lat_deg * DEG, sc.ship.lon_deg * DEG, 0.0)


def truth_records(sb: ShipBatch, d: dict[str, np.ndarray]) -> list[AircraftTruth]:
    """One AircraftTruth per ship sample of sb from the kinematics' truth arrays d (each (K, ...)),
    with the misalignment the aircraft's axes make with the ship's."""
    rel = relative_rotvec_batch(sb.q_nb, d['q_nb'])
    return [AircraftTruth(t_ns=int(sb.t_ns[k]), p_w=d['p_w'][k], q_nb=d['q_nb'][k], v_b=d['v_b'][k],
                          w_b=d['w_b'][k], misalignment=rel[k], on_deck=bool(d['on_deck'][k]))
            for k in range(len(sb))]


BATCH_SAMPLES = 6000
"""Samples per batch of the slave IMU's synthesis and of the LDV stream's decoding in the batch
pipeline (60 s at 100 Hz): their temporaries, some 2 kB per sample, stay this size (12 MB)
instead of growing with the run."""


class SlaveImuStage:
    """Ship sample in -> aircraft truth and (from the second sample on) a slave IMU sample."""

    def __init__(self, sc: Scenario) -> None:
        self.t0 = sc.t0_ns
        self.kin = AircraftKinematics(sc.aircraft, plane_of(sc), sc.rate_hz, sc.imu.output, sc.seed)
        self.errors = ImuErrorModel(sc.imu, sc.seed)
        self.prev: ShipSample | None = None

    def run_batch(self, sb: ShipBatch) -> tuple[dict[str, np.ndarray], list[ImuSample]]:
        """All samples of a run, batched BATCH_SAMPLES at a time (the same numbers as calling `step`
        on each in turn, for any batch size: `step_many`), so that the kinematics' per-sample
        temporaries (rotations, the quadrature nodes' rates and forces) stay a batch's size
        instead of growing with the run. Afterwards `errors.last_bias` holds the run's biases, one
        row (6,) per IMU sample."""
        tau = (sb.t_ns - self.t0) / 1e9
        truths: list[dict[str, np.ndarray]] = []
        imu: list[ImuSample] = []
        biases = [np.zeros((0, 6))]
        for a in range(0, len(sb), BATCH_SAMPLES):
            b = min(a + BATCH_SAMPLES, len(sb))
            truths.append(self.kin.truth_batch(sb.slice(slice(a, b)), tau[a:b]))
            lo = max(a - 1, 0)                          # the interval ending at sample a starts at a - 1
            if lo + 1 < b:
                dth, dv = self.kin.increments_batch(sb.slice(slice(lo, b - 1)), sb.slice(slice(lo + 1, b)),
                                                    tau[lo:b - 1], tau[lo + 1:b])
                gyro, accel = self.errors.measure_batch(dth, dv, tau[lo + 1:b] - tau[lo:b - 1])
                imu.extend(ImuSample(*rows) for rows in zip(sb.t_ns[lo + 1:b].tolist(), gyro, accel))
                biases.append(self.errors.last_bias)
        truth = {key: np.concatenate([t[key] for t in truths]) for key in truths[0]}
        self.errors.last_bias = np.concatenate(biases)
        self.prev = sb.sample(len(sb) - 1)
        return truth, imu

    def step_many(self, samples: Sequence[ShipSample]) -> list[tuple[AircraftTruth, ImuSample | None]]:
        """`step` on each of K ship samples in turn, as one batched call: the same records, bit
        for bit, and the same state afterwards (`prev`; the kinematics' gear, flexure and flight
        path; the error model's random streams, bias processes and quantiser), for any split of
        a run into chunks. Afterwards `errors.last_bias` holds one row (6,) per IMU sample
        returned, in order (unchanged when none is), as `step` leaves one."""
        if not samples:
            return []
        sb = ShipBatch.of(list(samples))
        tau = (sb.t_ns - self.t0) / 1e9                                  # tau_of, elementwise
        out: list[tuple[AircraftTruth, ImuSample | None]] = [
            (truth, None) for truth in truth_records(sb, self.kin.truth_batch(sb, tau))]
        prev = self.prev
        first = 0 if prev is not None else 1                             # index of the first IMU sample
        if first < len(sb):
            ends = sb if prev is None else ShipBatch.of([prev, *samples])
            tau_e = tau if prev is None else np.concatenate([[tau_of(prev.t_ns, self.t0)], tau])
            dth, dv = self.kin.increments_batch(ends.slice(slice(0, -1)), ends.slice(slice(1, None)),
                                                tau_e[:-1], tau_e[1:])
            gyro, accel = self.errors.measure_batch(dth, dv, tau_e[1:] - tau_e[:-1])
            for j in range(len(gyro)):
                k = first + j
                out[k] = (out[k][0], ImuSample(t_ns=int(sb.t_ns[k]), gyro=gyro[j], accel=accel[j]))
        self.prev = samples[-1]
        return out

    def step(self, s: ShipSample) -> tuple[AircraftTruth, ImuSample | None]:
        tau = tau_of(s.t_ns, self.t0)
        truth = self.kin.truth(s, tau)
        imu = None
        if self.prev is not None:
            tau_p = tau_of(self.prev.t_ns, self.t0)
            dth, dv = self.kin.increments(self.prev, s, tau_p, tau)
            imu = self.errors.measure(s.t_ns, dth, dv, tau - tau_p)
        self.prev = s
        return truth, imu


@dataclass
class BatchResult:
    scenario: Scenario
    estimates: list[Estimate]
    truth: list[AircraftTruth] = field(repr=False)
    filter: TransferAlignment = field(repr=False)
    wall_time_s: float = 0.0


def ship_source(sc: Scenario) -> PaperShipMotion:
    """The ship model for `sc.ship.mode` ('paper' or 'spectral'); both have
    `sample_batch(t, t0_ns, dt_ns, k0)` and `samples(t, t0_ns, dt_ns, k0)`."""
    return make_motion(sc.ship, sc.seed)


def ship_batch(sc: Scenario) -> ShipBatch:
    """The ship truth at every sample of the run."""
    k = np.arange(sc.n_samples)
    taus = (k * sc.dt_ns) / 1e9
    return ship_source(sc).sample_batch(taus, sc.t0_ns, sc.dt_ns)


def ship_samples(sc: Scenario) -> list[ShipSample]:
    """`ship_batch` as samples."""
    return split(ship_batch(sc))


@dataclass
class Inputs:
    """Everything the filter and the evaluation see, for a whole scenario. Sensor streams
    hold what their nodes publish (own rate, stamps = validity time + latency). `doppler` is
    None unless doppler.enabled. `sensor_truth` (what /truth/imu_bias and
    /truth/master_error carry, at every sample): imu_t_ns (K-1,), imu_gyro_bias,
    imu_accel_bias (K-1, 3) in aircraft axes; master_t_ns (stamps of `master`),
    master_phi, master_dv (nav frame)."""
    ships: ShipBatch
    truth: dict[str, np.ndarray]
    imu: list[ImuSample]
    master: list[MasterSample]
    ldv: list[LdvSample]
    doppler: list[DopplerSample] | None = None
    sensor_truth: dict[str, np.ndarray] = field(default_factory=dict)


def simulate(sc: Scenario) -> Inputs:
    """Ship, slave IMU, master INS and LDV for the whole run, vectorised (the same numbers
    the nodes produce sample by sample)."""
    ships = ship_batch(sc)
    slave = SlaveImuStage(sc)
    truth, imu = slave.run_batch(ships)
    masters = MasterInsStage(sc.master, sc.seed, sc.ship.lat_deg * DEG, sc.rate_hz, sc.t0_ns).run_batch(ships)
    ldv = LdvStage(sc.ldv, sc.seed, plane_of(sc), sc.rate_hz, sc.t0_ns).run_batch(
        ships, truth['p_w'], truth['q_nb'], truth['v_b'], truth['w_b'])
    doppler = None
    if sc.doppler.enabled:
        doppler = DopplerStage(sc.doppler, sc.seed, sc.rate_hz, sc.t0_ns).run_batch(ships.t_ns, truth['v_b'])
    bias = slave.errors.last_bias
    sensor_truth = {'imu_t_ns': ships.t_ns[1:].copy(), 'imu_gyro_bias': bias[:, :3], 'imu_accel_bias': bias[:, 3:],
                    'master_t_ns': np.array([o.t_ns for o in masters], dtype=np.int64),
                    'master_phi': np.array([o.phi for o in masters]).reshape(-1, 3),
                    'master_dv': np.array([o.dv for o in masters]).reshape(-1, 3),
                    'mounting': slave.kin.mu.copy()}
    return Inputs(ships, truth, imu, [o.sample for o in masters], ldv, doppler, sensor_truth)


def align(sc: Scenario, inp: Inputs, final: bool = True) -> TransferAlignment:
    """Feed the inputs to a fresh filter in the order the graph's nodes publish them, then
    flush it (final False: no flush, as a node that never learns its inputs ended)."""
    filt = TransferAlignment(sc.filter, plane_of(sc), sc.rate_hz)
    j_master = j_dop = 0                # sensor streams with their own rate / latency: pushed by stamp
    doppler = inp.doppler or []
    ldv = ldv_wire.transmitted_stream(inp.ldv, BATCH_SAMPLES)   # as the filter node decodes the messages
    next_ldv = next(ldv, None)
    for k in range(len(inp.ships)):
        t = int(inp.ships.t_ns[k])
        if k > 0:
            filt.push_imu(inp.imu[k - 1])
        while next_ldv is not None and next_ldv.t_ns <= t:
            filt.push_ldv(next_ldv)
            next_ldv = next(ldv, None)
        while j_dop < len(doppler) and doppler[j_dop].t_ns <= t:
            filt.push_doppler(doppler[j_dop])
            j_dop += 1
        while j_master < len(inp.master) and inp.master[j_master].t_ns <= t:
            filt.push_master(inp.master[j_master])
            j_master += 1
        filt.process()
    if final:
        filt.process(final=True)
    return filt


def run(sc: Scenario, keep_truth: bool = True) -> BatchResult:
    """Run the whole scenario in-process; returns the filter outputs and the truth."""
    wall = time.perf_counter()
    inp = simulate(sc)
    filt = align(sc, inp)
    truths = truth_records(inp.ships, inp.truth) if keep_truth else []
    return BatchResult(sc, list(filt.outputs), truths, filt, time.perf_counter() - wall)
