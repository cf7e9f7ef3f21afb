"""The transfer-alignment engine's read-only views (docs/engine.md, using it): its outputs, the
published view, counters, diagnostics, the live solution, corrections, deck motion and health.
A mixin of TransferAlignment (engine.py), which owns the state these read."""
from __future__ import annotations

import dataclasses

from alignment_core.estimation import status
from alignment_core.estimation.consistency import NisMonitor
from alignment_core.estimation.deck_run import DeckRun
from alignment_core.estimation.health import ERROR
from alignment_core.estimation.input_streams import InputStreams
from alignment_core.estimation.launch_detection import LaunchDetector
from alignment_core.estimation.matching import LiveSolution, MatchResults
from alignment_core.estimation.models import Corrections, ErrorModel
from alignment_core.estimation.outputs import Counters, DeckMotion, Diagnostics, Estimate, Report
from alignment_core.estimation.publication import EstimateMaker
from alignment_core.estimation.relative_velocity import RelativeVelocity
from alignment_core.estimation.whiteness import InnovationWhiteness
from alignment_core.navigation.strapdown import NavState


class EngineViews:
    """Read-only properties over the engine's state (copies, never a reference into it)."""
    _outputs: list[Estimate]
    _published: list[Estimate]
    _counters: Counters
    _inputs: InputStreams
    _maker: EstimateMaker
    _live: LiveSolution | None
    _health: status.Health
    _monitor: NisMonitor
    _matching: bool
    _results: MatchResults
    _launch: LaunchDetector
    _deck: DeckRun
    _model: ErrorModel
    _rel: RelativeVelocity
    _whiteness: InnovationWhiteness

    @property
    def outputs(self) -> tuple[Estimate, ...]:
        """Every estimate so far, one per output instant (the filter's own, for scoring)."""
        return tuple(self._outputs)

    @property
    def published(self) -> tuple[Estimate, ...]:
        """What a node publishes for each output: never non-finite or absurd, the last good
        estimate held from an ERROR on (publication.py)."""
        return tuple(self._published)

    @property
    def latest(self) -> Estimate | None:
        return self._outputs[-1] if self._outputs else None

    @property
    def counters(self) -> Counters:
        """A copy of the counters."""
        return dataclasses.replace(self._counters)

    @property
    def last_rejection(self) -> str:
        """Why the last sample pushed was rejected ('' if it was accepted)."""
        return self._inputs.last_rejection

    def report(self, level: int | None = None, flags: tuple[str, ...] = ()) -> Report:
        """The /diagnostics status as of the stamps processed so far (status.py): the estimates'
        (breakdown, inconsistent, gap; or the given level and flags), WARN for a silent master or
        LDV and for any input trouble so far (input_streams.py), and its message."""
        if level is None:
            level, flags = status.level_and_flags(self._health, self._monitor)
        trouble = status.input_trouble(self._counters, self._inputs.rejections)
        return status.report(level, flags, self._health, self._monitor, self._matching, self._inputs.silent(),
                             trouble, self.relative_velocity)

    def status(self) -> tuple[int, tuple[str, ...]]:
        """(level, flags) as of the stamps processed so far (report())."""
        r = self.report()
        return r.level, r.flags

    def waiting_for(self) -> tuple[str, ...]:
        """The master or LDV the stamp order waits for that has delivered nothing while the other
        streams ran silence_warn_s (arrival liveness: what a node is waiting for now)."""
        return self._inputs.waiting_for()

    def diagnostics(self) -> Diagnostics:
        """The filter's diagnostics as of the last output, the status now, failure, message and
        queued samples, and the consistency monitor's last window."""
        if self._maker.held is not None:
            filt = dict(self._maker.held[2])
        else:
            filt = {} if self._live is None else self._live.kf.diagnostics()
        r = self.report()
        return Diagnostics(filt, self.healthy, self.failure, self._inputs.pending(), r.level, r.flags, r.message,
                           self._inputs.silent(),
                           self._monitor.summary(), self.relative_velocity, self._whiteness.summary())

    @property
    def solution(self) -> NavState | None:
        """A copy of the live slave solution (None before initialisation)."""
        if self._live is None:
            return None
        st = self._live.ins.s
        return dataclasses.replace(st, q_nb=st.q_nb.copy(), v_n=st.v_n.copy(), prev_dtheta=st.prev_dtheta.copy(),
                                   prev_dv=st.prev_dv.copy())

    @property
    def corrections(self) -> Corrections:
        """A copy of what feedback accumulated outside the strapdown (sensor biases, lever arm)."""
        c = self._results.corr
        return Corrections(bg=c.bg.copy(), ba=c.ba.copy(), dr=c.dr.copy(), mu=c.mu.copy())

    @property
    def deck_motion(self) -> DeckMotion:
        d = self._launch
        return DeckMotion(d.moving, d.t_moving_ns, d.t_launch_ns, self._deck.displacement.copy())

    @property
    def labels(self) -> tuple[str, ...]:
        return self._model.labels

    @property
    def state_labels(self) -> tuple[str, ...]:
        """The published names of the states, with their SI unit (Estimate.state, state_estimate.py)."""
        return self._maker.state.labels

    @property
    def relative_velocity(self) -> str:
        """Where the relative velocity comes from now: 'ldv', 'zero', 'zero (no LDV stream)' or
        'ldv silent after t = ... s' (relative_velocity.py)."""
        rel = self._rel
        if rel.t_silent_ns is not None:
            return f'{rel.mode} after t = {rel.t_silent_ns * 1e-9:.3f} s'
        return rel.mode

    @property
    def whiteness(self) -> InnovationWhiteness:
        """The innovation whiteness test (its windows so far: `history`, `last`; whiteness.py)."""
        return self._whiteness

    @property
    def n_states(self) -> int:
        return self._model.n

    @property
    def model_name(self) -> str:
        return self._model.name

    @property
    def uses_doppler(self) -> bool:
        return self._model.uses_doppler

    @property
    def healthy(self) -> bool:
        """False at level ERROR: a breakdown, an inconsistent filter, an unrecovered long gap."""
        return status.level_and_flags(self._health, self._monitor)[0] < ERROR

    @property
    def failure(self) -> str:
        """Why the estimate is not healthy ('' while it is)."""
        return status.failure(self._health, self._monitor)
