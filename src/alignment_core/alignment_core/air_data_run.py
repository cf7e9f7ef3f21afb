"""A whole air-data run in-process (the same streams the graph's nodes produce): the aircraft's
truth, its IMU, the FADS frames (sensors/fads.py), the INS the estimator reads (a reference INS,
or the transfer-aligned slave INS of the alignment filter), then the air-data estimator of
`air_data_filter` (paper or tight form, EKF / UKF / CKF). Estimates are taken at every frame."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from alignment_core import pipeline
from alignment_core.air_data.ports import PortModel
from alignment_core.config.scenario import Scenario
from alignment_core.estimation.air_data.config import AirDataFilterConfig
from alignment_core.estimation.air_data.inputs import InsSample
from alignment_core.estimation.air_data.outputs import AIR_DATA_LABELS
from alignment_core.estimation.air_data.paper_form import PaperAirDataFilter
from alignment_core.estimation.air_data.tight_form import TightAirDataFilter
from alignment_core.geometry.rotations import quat_to_dcm_batch
from alignment_core.samples import ImuSample, ShipBatch
from alignment_core.sensors.fads import FadsFrame, FadsStage
from alignment_core.sensors.reference_ins import ReferenceInsStage


@dataclass
class AirDataInputs:
    """t_ns (K,) of the truth samples with q_nb (K, 4), v_enu (K, 3), lat, lon, h (K,); the IMU
    samples (K - 1); the FADS frames; the INS solutions the estimator reads."""
    t_ns: np.ndarray
    q_nb: np.ndarray
    v_enu: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    h: np.ndarray
    imu: list[ImuSample]
    frames: list[FadsFrame]
    ins: list[InsSample]


@dataclass
class AirDataRun:
    """Per frame k: t (K,) s since the start, the truth and the estimate of AIR_DATA_LABELS
    (K, L) with the estimate's sigma, healthy (K,); the estimator's counters, the ports it
    excluded and when."""
    t: np.ndarray
    labels: tuple[str, ...]
    truth: np.ndarray
    value: np.ndarray
    sigma: np.ndarray
    healthy: np.ndarray
    counts: dict[str, int] = field(default_factory=dict)
    excluded_ports: tuple[int, ...] = ()
    detections: list[tuple[float, int]] = field(default_factory=list)


def _reference_ins(sc: Scenario, t_ns, q_nb, v_enu, lat, lon, h) -> list[InsSample]:
    stage = ReferenceInsStage(sc.reference_ins, sc.seed, sc.t0_ns)
    out = []
    for k in range(len(t_ns)):
        s = stage.step(int(t_ns[k]), q_nb[k], v_enu[k], lat[k], lon[k], h[k])
        if s is not None:
            out.append(InsSample((s.t_ns - sc.t0_ns) * 1e-9, s.q_nb, s.v_enu, s.h, s.lat, s.att_cov, s.vel_cov,
                                 s.height_var))
    return out


def _aligned_ins(sc: Scenario, inp: pipeline.Inputs) -> list[InsSample]:
    """The transfer-aligned slave INS as the alignment filter publishes it (/alignment/odom):
    its corrected solution at every output, with its covariance."""
    plane = pipeline.plane_of(sc)
    out = []
    for e in pipeline.align(sc, inp).outputs:
        if e.p_w is None or e.v_b is None or e.pose_cov is None or e.twist_cov is None or not e.healthy:
            continue
        c = quat_to_dcm_batch(np.asarray(e.q_nb, dtype=float))
        lat, _, h = plane.to_geodetic(np.asarray(e.p_w, dtype=float))
        out.append(InsSample((e.navigation_ns - sc.t0_ns) * 1e-9, np.asarray(e.q_nb, dtype=float), c @ e.v_b, float(h),
                             float(lat), e.pose_cov[3:6, 3:6], c @ e.twist_cov[:3, :3] @ c.T, float(e.pose_cov[2, 2])))
    return out


def simulate(sc: Scenario) -> AirDataInputs:
    """Truth, IMU, FADS frames and the INS solutions (sc.air_data_filter.ins_source) for the whole run."""
    if not sc.fads.enabled:
        raise ValueError("the scenario has no FADS (fads.enabled false)")
    aligned = sc.air_data_filter.ins_source == 'aligned'
    if not aligned and not sc.reference_ins.enabled:
        raise ValueError("air_data_filter.ins_source 'reference' needs reference_ins.enabled")
    if aligned:
        inp = pipeline.simulate(sc)
        ships, truth, imu = inp.ships, inp.truth, inp.imu
    else:
        ships = ShipBatch.of(pipeline.ship_samples(sc))
        truth, imu = pipeline.SlaveImuStage(sc).run_batch(ships)
    lat, lon, h = pipeline.plane_of(sc).to_geodetic(truth['p_w'])
    v_enu = np.einsum('kij,kj->ki', quat_to_dcm_batch(truth['q_nb']), truth['v_b'])
    frames = FadsStage(sc.fads, sc.seed, sc.t0_ns).step_batch(ships.t_ns, truth['q_nb'], v_enu, h)
    ins = _aligned_ins(sc, inp) if aligned else _reference_ins(sc, ships.t_ns, truth['q_nb'], v_enu, lat, lon, h)
    return AirDataInputs(ships.t_ns, truth['q_nb'], v_enu, lat, lon, h, imu, frames, ins)


def make_estimator(cfg: AirDataFilterConfig, sc: Scenario) -> PaperAirDataFilter | TightAirDataFilter:
    model = PortModel(sc.fads.geometry, sc.fads.epsilon)
    if cfg.form == 'paper':
        return PaperAirDataFilter(cfg, model, 1.0 / sc.rate_hz)
    return TightAirDataFilter(cfg, model, sc.fads.period_ns * 1e-9)


IMU_BLOCK_S = 0.1
"""The paper form propagates over blocks of IMU samples (their mean specific force and rate):
the node does the same."""


def estimate(sc: Scenario, inp: AirDataInputs, **overrides) -> AirDataRun:
    """Run the estimator of sc.air_data_filter (fields replaced by `overrides`) over the inputs,
    pushing INS, IMU (in blocks of IMU_BLOCK_S) and frames in stamp order."""
    cfg = dataclasses.replace(sc.air_data_filter, **overrides)
    est = make_estimator(cfg, sc)
    t0 = sc.t0_ns
    paper = isinstance(est, PaperAirDataFilter)
    j_ins = 0
    truth_rows, values, sigmas, ok, times = [], [], [], [], []
    imu_by_t = {s.t_ns: s for s in inp.imu} if paper else {}
    block = max(1, int(round(IMU_BLOCK_S * sc.rate_hz)))
    acc = np.zeros(3), np.zeros(3)
    t_block = (int(inp.t_ns[0]) - t0) * 1e-9
    frames = iter(inp.frames)
    frame = next(frames, None)
    for k in range(len(inp.t_ns)):
        t_ns = int(inp.t_ns[k])
        while j_ins < len(inp.ins) and inp.ins[j_ins].t <= (t_ns - t0) * 1e-9 + 1e-12:
            est.push_ins(inp.ins[j_ins])
            j_ins += 1
        if isinstance(est, PaperAirDataFilter) and k > 0:
            s = imu_by_t[t_ns]
            acc = acc[0] + s.accel, acc[1] + s.gyro
            if k % block == 0 or k == len(inp.t_ns) - 1:
                n = (k - 1) % block + 1
                t_now = (t_ns - t0) * 1e-9
                est.push_imu(t_block, t_now, acc[0] / n, acc[1] / n)
                acc, t_block = (np.zeros(3), np.zeros(3)), t_now
        while frame is not None and frame.t_ns <= t_ns:
            t = (frame.t_ns - t0) * 1e-9
            est.push_frame(t, frame.pressures_pa)
            e = est.estimate(t)
            if e is not None:
                truth_rows.append(frame.truth.vector()[:len(AIR_DATA_LABELS)])
                values.append(e.value[:len(AIR_DATA_LABELS)])
                sigmas.append(e.sigma[:len(AIR_DATA_LABELS)])
                ok.append(e.healthy)
                times.append(t)
            frame = next(frames, None)
    tight = est if isinstance(est, TightAirDataFilter) else None
    return AirDataRun(np.array(times), AIR_DATA_LABELS, np.array(truth_rows), np.array(values), np.array(sigmas),
                      np.array(ok), dict(est.counts), tight.excluded_ports if tight is not None else (),
                      list(tight.detector.detections) if tight is not None else [])
