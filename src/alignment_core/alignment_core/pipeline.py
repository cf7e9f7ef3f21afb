"""The batch pipeline: the graph's stages wired in-process, in the same order and with the
same records the nodes exchange, so both give the same numbers for a scenario and seed."""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from . import earth
from .aircraft import AircraftKinematics
from .attitude import DEG
from .samples import AircraftTruth, ImuSample, LdvSample, MasterSample, ShipSample
from .scenario import Scenario, tau_of
from .sensors import ImuErrorModel, LdvModel, MasterInsModel
from .ship import PaperShipMotion
from .transfer_alignment import Estimate, TransferAlignment


def plane_of(sc: Scenario) -> earth.TangentPlane:
    return earth.TangentPlane(sc.ship.lat_deg * DEG, sc.ship.lon_deg * DEG, 0.0)


class SlaveImuStage:
    """Ship sample in -> aircraft truth and (from the second sample on) a slave IMU sample."""

    def __init__(self, sc: Scenario) -> None:
        self.t0 = sc.t0_ns
        self.kin = AircraftKinematics(sc.aircraft, plane_of(sc), sc.rate_hz)
        self.errors = ImuErrorModel(sc.imu, sc.seed)
        self.prev: ShipSample | None = None

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
    return PaperShipMotion(sc.ship, sc.seed)


def ship_samples(sc: Scenario) -> list[ShipSample]:
    k = np.arange(sc.n_samples)
    taus = (k * sc.dt_ns) / 1e9
    return ship_source(sc).samples(taus, sc.t0_ns, sc.dt_ns)


def run(sc: Scenario, keep_truth: bool = True) -> BatchResult:
    """Run the whole scenario in-process; returns the filter outputs and the truth."""
    wall = time.perf_counter()
    ships = ship_samples(sc)
    slave = SlaveImuStage(sc)
    master = MasterInsModel(sc.master, sc.seed, sc.ship.lat_deg * DEG)
    ldv = LdvModel(sc.ldv, sc.seed)
    filt = TransferAlignment(sc.filter, plane_of(sc), sc.rate_hz)
    truths: list[AircraftTruth] = []
    for s in ships:
        truth, imu = slave.step(s)
        if keep_truth:
            truths.append(truth)
        m: MasterSample = master.measure(s)
        ld: LdvSample = ldv.measure(s, truth)
        if imu is not None:
            filt.push_imu(imu)
        filt.push_ldv(ld)
        filt.push_master(m)
        filt.process()
    filt.process(final=True)
    return BatchResult(sc, filt.outputs, truths, filt, time.perf_counter() - wall)
