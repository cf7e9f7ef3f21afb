"""Matching: a master or Doppler sample and the slave solution at its time of validity made into a
filter update (delay-aware H Phi^-1), and the estimate fed back into the live and the stored slave
solutions. The engine's collaborator; it decides nothing about when to match (docs/engine.md)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, cast

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.compiled import FLOAT64, as_float64
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.delay_inputs import DelayInputs, Extras
from alignment_core.estimation.filter_factory import EngineFilter
from alignment_core.estimation.filters.base import NonlinearFilter, solve
from alignment_core.estimation.filters.kalman import KalmanFilter
from alignment_core.estimation.filters.lowpass import ButterworthLowPass
from alignment_core.estimation.health import check_health
from alignment_core.estimation.match_step import layers_of, update_and_feed_back
from alignment_core.estimation.models import Corrections, ErrorModel, Match, Measurement, Propagation
from alignment_core.estimation.models.beam import project_on_beam
from alignment_core.estimation.outputs import Counters
from alignment_core.estimation.reference_force import SpotAcceleration
from alignment_core.estimation.reference_velocity import (
    DISPLACEMENT,
    SURVEYED,
    SURVEYED_CORRECTED,
    Reference,
    reference_and_fit,
    reference_velocities,
)
from alignment_core.geometry.rotations import floats, quat_mul_f, quat_to_dcm
from alignment_core.navigation.history import LdvRecord, Past, SlaveHistory, SlaveSnapshot
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.samples import DopplerSample, MasterSample
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

PastState = tuple[NavState, np.ndarray | None]       # the slave at a validity time, Phi from there to now
_NONE = np.empty(0)                                  # no beam, as the kernel takes it


class _DopplerModel(Protocol):
    def doppler_measurement(self, v_n: np.ndarray, z: np.ndarray, r: np.ndarray | None = None) -> Measurement: ...


@dataclass
class LiveSolution:
    """The slave strapdown at t_ns, the filter estimating its errors and the slave's past
    solutions over the last IMU steps (created at initialisation)."""
    ins: Strapdown
    kf: EngineFilter
    t_ns: int
    history: SlaveHistory
    prop: Propagation | None = None         # the last IMU step as the model saw it (gap bridging)
    gyro: np.ndarray | None = None          # the last raw gyro rate (the published body rate)


@dataclass
class MatchResults:
    """What the matches leave: the published misalignment and its 1-sigma (rad, aircraft axes),
    the last a-posteriori state before feedback, the last NIS, the stamp of the last accepted
    Doppler update, and the corrections fed back outside the strapdown (sensor biases, lever arm);
    the rows of the last update (its NIS's degrees of freedom) and, from the last accepted master
    update, the master attitude and the corrected slave attitude at its validity time (the
    relative attitude a bridged gap carries the slave across with)."""
    mu: np.ndarray
    mu_sigma: np.ndarray
    x: np.ndarray
    nis: float = math.nan
    t_doppler_update: int | None = None
    corr: Corrections = field(default_factory=Corrections)
    dof: int = 0
    anchor: tuple[np.ndarray, np.ndarray] | None = None    # (C_m (3, 3), slave q_nb (4,))
    innovation: np.ndarray | None = None   # the last accepted master update's innovation and its
    innovation_cov: np.ndarray | None = None   # covariance S (innovation whiteness)
    t_mu: int | None = None                # the validity time of `mu`: its master update's (None: none yet)


class Matcher:
    """Master and Doppler updates for one engine: the reference (lever arm, deck velocity), the
    measurement from the model, the update and the closed-loop feedback."""

    def __init__(self, cfg: FilterConfig, model: ErrorModel, imu_rate_hz: float, span_ns: int,
                 counters: Counters) -> None:
        self._cfg = cfg
        self._model = model
        self._layers = layers_of(model)      # velocity matching and its layers: match_step.py
        self._counters = counters
        self._compensate = cfg.lever_arm_treatment == 'compensation'
        self._r0 = np.array(cfg.lever_arm_m, dtype=np.float64)
        # the lever arm put into the reference (ship axes): the surveyed spot (plus the estimated
        # correction) under compensation, and the LDV-integrated deck displacement
        self._arm = (DISPLACEMENT if not self._compensate else
                     SURVEYED_CORRECTED if cfg.lever_arm_states else SURVEYED)
        self._lowpass: ButterworthLowPass | None = None
        if cfg.lever_arm_treatment == 'butterworth':
            if not cfg.butterworth_cutoff_hz < 0.5 * imu_rate_hz:
                raise ConfigError(f"filter.butterworth_cutoff_hz = {cfg.butterworth_cutoff_hz} must be below the "
                                  f"Nyquist frequency {0.5 * imu_rate_hz} Hz of the {imu_rate_hz} Hz matching rate")
            self._lowpass = ButterworthLowPass(cfg.butterworth_cutoff_hz, imu_rate_hz)
        self._r_moving = np.eye(3) * (cfg.ldv_sigma_mps**2 + cfg.master_velocity_sigma_mps**2)
        self._r_parked = np.eye(3) * (cfg.parked_velocity_sigma_mps**2 + cfg.master_velocity_sigma_mps**2)
        self._gate = cfg.gate_chi2 if cfg.gate_chi2 > 0.0 else None
        self._gated_in_row = 0               # a run this long means the state, not the data, is off
        self._doppler_lat_ns = int(round(cfg.doppler_latency_s * 1e9))
        psi = cfg.heading_on_deck_deg * DEG
        # nominal mounting on the deck: C_a^s = Rz(-heading on deck) (None: the identity)
        self.c_nom = None if psi == 0.0 else Rotation.from_rotvec([0.0, 0.0, -psi]).as_matrix()
        self.spot: SpotAcceleration | None = None    # the spot's acceleration fitted to the master samples (engine's)
        # rate matching / delay state: the last IMU intervals and the previous master sample
        self.tracks_intervals = cfg.rate_matching or cfg.master_delay_state
        self.delay_inputs = DelayInputs(cfg, imu_rate_hz, span_ns, counters)
        self.results = MatchResults(mu=np.zeros(3), mu_sigma=np.full(3, cfg.init_attitude_sigma_deg * DEG),
                                    x=np.zeros(model.n))

    def use_rigid_noise(self) -> None:
        """Relative velocity zero (a rigid mount, estimation/relative_velocity.py): every match is
        parked, with the rigid-mount noise."""
        self._r_parked = np.eye(3) * (self._cfg.rigid_velocity_sigma_mps**2 + self._cfg.master_velocity_sigma_mps**2)

    def restart(self, imu_rate_hz: float) -> None:
        """Forget what ties the matches to the slave's past (after a bridged IMU gap): the low-pass
        filter's state, the IMU intervals and the previous master sample, the gated run."""
        if self._lowpass is not None:
            self._lowpass = ButterworthLowPass(self._cfg.butterworth_cutoff_hz, imu_rate_hz)
        self.delay_inputs.restart()
        self._gated_in_row = 0

    def _gate_now(self) -> float | None:
        """The gate for the next update: none once gate_release_updates updates in a row were gated
        (a filter that rejects all its data has a wrong state; the consistency monitor sees it)."""
        if self._gate is not None and self._gated_in_row >= self._cfg.gate_release_updates:
            return None
        return self._gate

    def _gated(self, accepted: bool, gate: float | None) -> bool:
        """Count the update's outcome; True if it was gated."""
        if accepted:
            if gate is None and self._gated_in_row:
                self._counters.gate_released += 1
            self._gated_in_row = 0
            return False
        self._gated_in_row += 1
        self._counters.gated += 1
        return True

    def reference(self, m: MasterSample, ldv: LdvRecord | None, deck_disp: np.ndarray,
                  surveyed: bool = False, fit_at: int | None = None) -> Reference:
        """The reference for the slave from master sample m and the LDV at its validity time;
        `surveyed`: with the surveyed lever arm whatever the treatment (where the slave is, to
        place it there after a gap), else the one the matches use. fit_at: the validity time to
        add the sample to the deck spot's fit at (`spot.add` with the reference's C_m and arm), in
        the same compiled call."""
        moving = ldv is not None and ldv.moving
        disp = ldv.disp if ldv is not None else deck_disp
        beam = ldv.beam if ldv is not None and ldv.valid else None
        # a beam LDV is the measurement parked too (its one row); a vector one only once moving
        v_rel = ldv.v_s if (ldv is not None and ldv.valid and (moving or beam is not None)) else np.zeros(3)
        arm = SURVEYED_CORRECTED if surveyed else self._arm
        q, w_b, v_b, dr = as_float64(m.q_nb), as_float64(m.w_b), as_float64(m.v_b), as_float64(self.results.corr.dr)
        disp, v_rel, beam_s = as_float64(disp), as_float64(v_rel), _NONE if beam is None else as_float64(beam)
        spot = self.spot
        if fit_at is None or spot is None:
            c_m, r, u_n, v_ref, beam_n, w_n = reference_velocities(q, w_b, v_b, self._r0, dr, disp, arm, v_rel, beam_s)
        else:
            c_m, r, u_n, v_ref, beam_n, w_n, start, fitted, slope = reference_and_fit(
                q, w_b, v_b, self._r0, dr, disp, arm, v_rel, beam_s, *spot.buffers(), fit_at)
            spot.take(start, fitted, slope)
        return Reference(c_m, r, v_rel, u_n, v_ref, moving, None if beam is None else beam_n, w_n)

    def extras(self, live: LiveSolution, t_v: int, m: MasterSample, ref: Reference) -> Extras:
        """The delay state's and rate matching's inputs of this match (delay_inputs.py), with
        the deck spot's fit and the gyro bias estimated so far."""
        return self.delay_inputs.at_match(live, t_v, m, ref, self.spot, self.results.corr.bg)

    def step_in_kernel(self, live: LiveSolution, past: Past) -> SlaveSnapshot | None:
        """The stored solution whose step into the live one the compiled update interpolates at
        `past` itself (match_step.py: velocity matching and its layers under the plain float64
        Kalman filter, no low-pass, a time inside the last step), else None: update_master then
        takes `past.state()`, which the engine makes first, where state_at was made."""
        kf = live.kf
        if self._layers is None or type(kf) is not KalmanFilter or kf.dtype is not FLOAT64 or self._lowpass is not None:
            return None
        return past.into_live()

    def update_master(self, live: LiveSolution, t_v: int, m: MasterSample, ref: Reference, ldv: LdvRecord,
                      past: Past, step: SlaveSnapshot | None, extras: Extras | None, ldv_spacing_ns: int,
                      master_spacing_ns: int) -> None:
        """Velocity (+ attitude) match at t_v. The innovation is formed against the slave solution
        at t_v; the error state is the live one (at live.t_ns), related to the one at t_v by the
        transitions in between, x(t_ins) = Phi x(t_v) (process noise over the latency neglected),
        so the measurement matrix is H Phi^-1 (identity at zero latency). The estimate is fed
        back into the live solution, and the same correction into the stored past ones. `past`:
        where t_v falls in the slave history; `step`: `step_in_kernel`'s."""
        uses_ldv = ref.moving or ref.beam_n is not None
        r_vel = self._r_moving if uses_ldv else self._r_parked
        if uses_ldv:
            # an LDV slower than the master enters several matches with the same noise:
            # weight it as one sample per LDV interval (variance times the matches per sample)
            ratio = ldv_spacing_ns / master_spacing_ns if master_spacing_ns else 1.0
            extra = ldv.var + (ratio - 1.0) * self._cfg.ldv_sigma_mps ** 2 if ratio > 1.0 else ldv.var
            if extra > 0.0:
                r_vel = r_vel + np.eye(3) * extra
        kf = live.kf
        if step is not None and self._update_compiled(live, cast(KalmanFilter, kf), t_v, m, ref, ref.v_ref, r_vel,
                                                      (step, past.f), None, extras):
            return
        compiled = self._layers is not None and type(kf) is KalmanFilter and kf.dtype is FLOAT64
        nav, phi_acc = past.state()
        z_vel = nav.v_n - ref.v_ref
        if self._lowpass is not None:
            z_vel = self._lowpass.step(z_vel)
        if compiled and (phi_acc is None or phi_acc.dtype == FLOAT64):
            self._update_compiled(live, cast(KalmanFilter, kf), t_v, m, ref, z_vel, r_vel, None, (nav, phi_acc),
                                  extras)
            return
        match = Match(c_m=ref.c_m, w_m=m.w_b, r=ref.r, u_n=ref.u_n, v_ref=ref.v_ref, z_vel=z_vel,
                      r_vel=r_vel, ins=nav, c_nom=self.c_nom)
        if extras is not None:
            match.w_n, match.a_n, match.rate = extras
        res = self.results
        meas = self._model.measurement(match, res.corr)
        if ref.beam_n is not None:
            meas = project_on_beam(meas, ref.beam_n)
        gate = self._gate_now()
        res.dof = len(meas.z)
        if meas.h is None:
            assert meas.hfun is not None
            upd = cast(NonlinearFilter, kf).update_nonlinear(meas.z, meas.hfun, meas.r, gate)
        else:
            h = meas.h if phi_acc is None else solve(phi_acc.T, meas.h.T).T
            upd = kf.update(meas.z, h, meas.r, gate)
        check_health(kf.x, kf.P)
        res.nis = upd.nis
        if self._gated(upd.accepted, gate):
            return
        self._counters.updates += 1
        res.innovation, res.innovation_cov = upd.innovation, upd.s
        x = kf.x
        res.x = x.copy()
        p = kf.P
        # no later master match needs the solutions before t_v (a later Doppler sample may)
        live.history.prune(min(t_v, live.t_ns - self._doppler_lat_ns), live.t_ns)
        x_new, nav = self._feed_back(live, x, p, match, nav)
        kf.x = x_new
        res.anchor = (ref.c_m, nav.q_nb)
        res.mu, res.mu_sigma = self._model.misalignment(x_new, p, match, nav, res.corr)
        res.t_mu = t_v

    def _update_compiled(self, live: LiveSolution, kf: KalmanFilter, t_v: int, m: MasterSample, ref: Reference,
                         z: np.ndarray, r_vel: np.ndarray, step: tuple[SlaveSnapshot, float] | None,
                         past: PastState | None, extras: Extras | None) -> bool:
        """update_master's measurement, update, feedback and misalignment for velocity matching
        and its delay and lever-arm layers under the plain Kalman filter, in one compiled call
        (match_step.py): with the slave's solution at t_v `past` and z = z_vel, or inside its
        last step `step` (the stored solution it starts from, the fraction) and z = v_ref. False:
        declined, nothing done (a step whose z_vel numpy would warn of)."""
        res = self.results
        gate = self._gate_now()
        res.dof = 3 if ref.beam_n is None else 1
        st = live.ins.s
        q_past = phi_acc = None
        if past is not None:
            nav, phi_acc = past
            q_past = None if nav is st else nav.q_nb
        q0, v0, pos0 = st.q_nb, st.v_n, (st.lat, st.lon, st.h)
        w_n, a_n = (None, None) if extras is None else extras[:2]
        assert self._layers is not None
        upd, fed = update_and_feed_back(kf, self._layers, z, ref.u_n, r_vel, gate, st, res.corr, ref.c_m,
                                        self.c_nom, m.w_b, a_n, w_n, ref.beam_n, q_past, phi_acc, step)
        if upd is None:
            return False
        res.nis = upd.nis
        if self._gated(upd.accepted, gate) or fed is None:
            return True
        self._counters.updates += 1
        res.innovation, res.innovation_cov = upd.innovation, upd.s
        res.x = fed.x
        live.history.prune(min(t_v, live.t_ns - self._doppler_lat_ns), live.t_ns)
        self._carry(live, q0, v0, pos0, st, fed.carried)      # nav's attitude: fed.q_valid
        kf.adopt_x(fed.x_kept)                         # the kernel's new array: no copy needed
        res.anchor = (ref.c_m, fed.q_valid)
        res.mu, res.mu_sigma = fed.mu, fed.mu_sigma
        res.t_mu = t_v
        return True

    def update_doppler(self, live: LiveSolution, t: int, s: DopplerSample, past: PastState) -> None:
        """Match the slave velocity to the radar's, resolved with the slave's own attitude, at the
        radar's validity time (the slave solution there, H Phi^-1 as for the master)."""
        nav, phi_acc = past
        v_d = quat_to_dcm(nav.q_nb) @ s.v_b
        r = np.eye(2) * s.sigma ** 2
        meas = cast(_DopplerModel, self._model).doppler_measurement(nav.v_n, (nav.v_n - v_d)[0:2], r)
        assert meas.h is not None
        h = meas.h if phi_acc is None else solve(phi_acc.T, meas.h.T).T
        kf = live.kf
        gate = self._gate_now()
        upd = kf.update(meas.z, h, meas.r, gate)
        check_health(kf.x, kf.P)
        res = self.results
        res.nis = upd.nis
        res.dof = len(meas.z)
        if self._gated(upd.accepted, gate):
            return
        self._counters.doppler_updates += 1
        x = kf.x
        res.x = x.copy()
        zero = np.zeros(3)
        match = Match(c_m=np.eye(3), w_m=zero, r=zero, u_n=zero, v_ref=v_d, z_vel=zero, r_vel=np.eye(3), ins=nav)
        kf.x, _ = self._feed_back(live, x, kf.P, match, nav)
        res.t_doppler_update = t

    def _feed_back(self, live: LiveSolution, x: np.ndarray, p: np.ndarray, match: Match, nav: NavState
                   ) -> tuple[np.ndarray, NavState]:
        """Apply the estimate to the live solution (the model's feedback) and the same correction
        to the stored past ones; return the state the filter keeps and `nav` (the solution at the
        match's validity time) corrected."""
        st = live.ins.s
        q0, v0, pos0 = st.q_nb, st.v_n, (st.lat, st.lon, st.h)
        x_new = self._model.feedback(x, p, match, st, self.results.corr)
        return x_new, self._carry(live, q0, v0, pos0, nav)

    def _carry(self, live: LiveSolution, q0: np.ndarray, v0: np.ndarray, pos0: tuple[float, float, float],
               nav: NavState, carried: tuple[SlaveSnapshot, np.ndarray, np.ndarray] | None = None) -> NavState:
        """The feedback that took the live solution from (q0, v0, pos0) to its state now, applied
        to the low-pass filter's memory, the stored past solutions (`carried`: one of them with
        its attitude and velocity so carried already) and `nav`; return `nav`."""
        st = live.ins.s
        if self._lowpass is not None:
            self._lowpass.shift(st.v_n - v0)
        if not live.history.items and nav is st:
            return nav
        dpos = (st.lat - pos0[0], st.lon - pos0[1], st.h - pos0[2])
        live.history.correct(q0, st.q_nb, v0, st.v_n, *dpos, carried=carried)
        if nav is not st:
            cx, cy, cz, cw = floats(q0)
            q_corr = quat_mul_f(floats(st.q_nb), (-cx, -cy, -cz, cw))     # floats: quat_mul(q, quat_conj(q0))
            q = np.array(quat_mul_f(q_corr, floats(nav.q_nb)))
            nav = NavState(q_nb=q / np.sqrt(q @ q), v_n=nav.v_n + (st.v_n - v0), lat=nav.lat + dpos[0],
                           lon=nav.lon + dpos[1], h=nav.h + dpos[2])
        return nav
