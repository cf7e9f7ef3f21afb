"""The experiment catalogue: named Monte Carlo experiments (sweeps of scenario overrides
times seeds), each with the paper's published numbers to put ours beside.

An experiment is data: a base scenario, a list of cells (one sweep point each: its table
values and the dotted scenario overrides that realise it), the score time, settling
thresholds, and reference rows. `quick` shrinks it (fewer seeds and cells, shorter runs)
for the tests without changing what is computed.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field, replace

from .monte_carlo import RunSpec

AXES = ('roll', 'pitch', 'yaw')     # ROS FLU: x = roll, y = pitch, z = yaw
DEG_TO_ARCMIN = 60.0


@dataclass(frozen=True)
class Cell:
    """One sweep point: `values` are its table columns, `overrides` realise it."""
    label: str
    values: tuple[tuple[str, object], ...]
    overrides: tuple[tuple[str, object], ...]


@dataclass(frozen=True)
class Reference:
    """A published result: matched to our cells whose values contain `match`; per-axis
    numbers in arcmin (None where the paper gives none); `what` says which statistic."""
    match: tuple[tuple[str, object], ...]
    arcmin: tuple[float | None, float | None, float | None]
    what: str = 'final error, one run'


@dataclass(frozen=True)
class Experiment:
    name: str
    title: str
    description: str
    scenario: str
    base: tuple[tuple[str, object], ...]
    cells: tuple[Cell, ...]
    seeds: int = 20
    score_at: str | float = 'release'
    settle_arcmin: tuple[float, float, float] = (1.0, 1.0, 1.0)
    references: tuple[Reference, ...] = ()
    reference_source: str = ''
    sweep: str = ''                  # numeric value column for "RMS vs ..." plots
    series: str = ''                 # value column whose cells get error-vs-time plots
    quick_base: tuple[tuple[str, object], ...] = ()
    quick_cells: int = 0             # 0 = all

    def specs(self, seeds: int | None = None, first_seed: int = 1) -> list[RunSpec]:
        """Every (cell, seed) run; seed numbers are first_seed .. first_seed + seeds - 1 in every cell,
        so cells are compared on the same random draws."""
        n = self.seeds if seeds is None else seeds
        out = []
        for cell, i in itertools.product(self.cells, range(n)):
            out.append(RunSpec(index=len(out), cell=cell.label, scenario=self.scenario,
                               overrides=self.base + cell.overrides, seed=first_seed + i,
                               score_at=self.score_at, settle_arcmin=self.settle_arcmin, values=cell.values))
        return out

    def quick(self, seeds: int = 2) -> Experiment:
        cells = self.cells[:self.quick_cells] if self.quick_cells else self.cells
        return replace(self, base=self.base + self.quick_base, cells=cells, seeds=seeds)


def grid(**axes: list[tuple[object, dict[str, object]]]) -> tuple[Cell, ...]:
    """Cells of the Cartesian product of named axes; each axis lists (value, overrides)."""
    names = list(axes)
    cells = []
    for combo in itertools.product(*(axes[n] for n in names)):
        values = tuple((n, v) for n, (v, _) in zip(names, combo))
        ov: dict[str, object] = {}
        for _, o in combo:
            ov.update(o)
        label = ' '.join(f'{n}={v}' for n, v in values)
        cells.append(Cell(label, values, tuple(ov.items())))
    return tuple(cells)


def _deg(*v: float | None) -> tuple[float | None, ...]:
    return tuple(None if x is None else x * DEG_TO_ARCMIN for x in v)


ALL_FILTERS = ('kf', 'stf', 'stf_multiple', 'fading_tested', 'carlson', 'ud', 'combined')

# seed 000 Table 1: final attitude error (deg) of one run, (roll, pitch, yaw) per vibration peak
SEED000_TABLE1 = {
    (5, 'kf'): (-0.46, 1.83, 1.71), (5, 'stf'): (-0.44, 0.32, 1.62),
    (10, 'kf'): (-0.45, 3.63, 1.78), (10, 'stf'): (-0.42, 0.85, 1.61),
    (20, 'kf'): (-0.45, 7.25, 1.92), (20, 'stf'): (-0.39, 1.92, 1.59),
}

SEED000 = Experiment(
    name='seed000_table1',
    title='Seed 000, Table 1: catapult alignment under nose-gear vibration, KF vs STF',
    description=(
        "Catapult launch alignment (seed 000): ship at sea state 4 (paper mode), 116 E 40 N, "
        "heading 30 deg, 10 kn; master 0.001 deg/h, 50 ug; slave 0.01 deg/h, 100 ug; LDV 0.01 m/s; "
        "mounting (10', 15', -30') in the paper's right-forward-up axes. 5 s of velocity matching on the "
        "deck (the paper copies the master attitude and matches during the 3 s stroke only), then the "
        "3 s 2 g stroke; nose-gear vibration on the forward and vertical accelerometers from the "
        "stroke start, 100 Hz, decaying to ~0 in 0.5 s. Scored at the release. Both IMU output models: "
        "'sample' = point samples (what the paper implicitly simulates: the 100 Hz vibration aliases "
        "to a near-constant accelerometer error), 'increment' = integrated increments (a real IMU)."),
    scenario='catapult',
    base=(('duration_s', 10.0), ('aircraft.catapult.launch_time_s', 5.0),
          ('aircraft.vibration.enabled', True), ('aircraft.vibration.mode', 'accelerometer')),
    cells=grid(vibration_mps2=[(v, {'aircraft.vibration.peak_mps2': float(v)}) for v in (0, 5, 10, 20)],
               filter=[(a, {'filter.algorithm': a}) for a in ('kf', 'stf')],
               imu_output=[(m, {'imu.output': m}) for m in ('sample', 'increment')]),
    seeds=20,
    score_at='release',
    references=tuple(Reference((('vibration_mps2', v), ('filter', a)), _deg(*r))
                     for (v, a), r in SEED000_TABLE1.items()),
    reference_source='Seed 000, Table 1 (final attitude error, degrees, one run; paper pitch/roll/yaw)',
    sweep='vibration_mps2',
    series='imu_output',
    quick_cells=8,
)

CATAPULT_GOAL = Experiment(
    name='catapult_goal',
    title='Catapult goal: a realistic carrier launch, every filter',
    description=(
        "Our own realistic catapult scenario: spectral sea state 5 (Bales Hs 3.25 m, ITTC, cos^2 "
        "spreading, head-bow seas), closed-form 310 m carrier RAOs; aircraft 100 m forward of the "
        "master INS; deck flexure (static 3', dynamic 3' / 3 s per axis); nose-gear vibration 20 m/s^2 "
        "as real airframe motion; integrated-increment IMU; 60 s deck matching, 3 s 2 g stroke. "
        "Scored at the release against the true master-to-aircraft attitude (mounting + flexure)."),
    scenario='catapult',
    base=(('ship.mode', 'spectral'), ('ship.sea_state', 5), ('ship.wave_heading_deg', 150.0),
          ('aircraft.lever_arm_m', [100.0, -15.0, 18.0]),
          ('aircraft.flexure.enabled', True),
          ('aircraft.vibration.enabled', True), ('aircraft.vibration.peak_mps2', 20.0),
          ('aircraft.vibration.mode', 'motion'), ('imu.output', 'increment')),
    cells=grid(filter=[(a, {'filter.algorithm': a}) for a in ALL_FILTERS]),
    seeds=20,
    score_at='release',
    series='filter',
    quick_base=(('duration_s', 20.0), ('aircraft.catapult.launch_time_s', 12.0)),
    quick_cells=2,
)

DECK_GOAL = Experiment(
    name='deck_goal',
    title='Deck goal: 300 s deck alignment across sea states, every filter at sea state 5',
    description=(
        "Our own realistic deck alignment: spectral sea states 3-7 (Bales table, ITTC, cos^2 "
        "spreading, waves 30 deg off the bow), closed-form 310 m carrier RAOs, aircraft 100 m forward of "
        "the master INS with deck flexure; 300 s of velocity matching with computational lever-arm "
        "compensation; error at 250 s (goal: 0.01 deg level, 0.1 deg yaw). Settling: the time after "
        "which the error stays within 0.6' (level) / 6' (yaw)."),
    scenario='deck',
    base=(('ship.mode', 'spectral'), ('ship.wave_heading_deg', 150.0),
          ('aircraft.lever_arm_m', [100.0, -15.0, 18.0]), ('aircraft.flexure.enabled', True)),
    cells=(grid(sea_state=[(s, {'ship.sea_state': s}) for s in (3, 4, 5, 6, 7)],
                filter=[('kf', {'filter.algorithm': 'kf'})])
           + grid(sea_state=[(5, {'ship.sea_state': 5})],
                  filter=[(a, {'filter.algorithm': a}) for a in ALL_FILTERS if a != 'kf'])),
    seeds=10,
    score_at=250.0,
    settle_arcmin=(0.6, 0.6, 6.0),
    sweep='sea_state',
    series='sea_state',
    quick_base=(('duration_s', 30.0),),
    quick_cells=2,
)


CONSISTENCY_CATAPULT = Experiment(
    name='consistency_catapult',
    title='Consistency: 50 runs of the default catapult scenario, recommended filter',
    description=(
        "The default `catapult` scenario (seed 000's conditions with 60 s of deck matching at sea state 4, "
        "the 3 s 2 g stroke, no vibration, increment IMU) with the default (recommended) filter, 50 seeds. "
        "An honest filter's average 3-dof misalignment NEES lies inside the 95 % chi-square bounds."),
    scenario='catapult',
    base=(),
    cells=(Cell('default', (('filter', 'default'),), ()),),
    seeds=50,
    score_at='release',
    series='filter',
    quick_base=(('duration_s', 15.0), ('aircraft.catapult.launch_time_s', 8.0)),
)

CONSISTENCY_DECK = Experiment(
    name='consistency_deck',
    title='Consistency: 50 runs of the default deck scenario, recommended filter',
    description=(
        "The default `deck` scenario (300 s of velocity matching at sea state 4, paper-mode ship) with the "
        "default (recommended) filter, 50 seeds, scored at 250 s. An honest filter's average 3-dof "
        "misalignment NEES lies inside the 95 % chi-square bounds."),
    scenario='deck',
    base=(),
    cells=(Cell('default', (('filter', 'default'),), ()),),
    seeds=50,
    score_at=250.0,
    settle_arcmin=(0.6, 0.6, 6.0),
    series='filter',
    quick_base=(('duration_s', 20.0),),
)


@dataclass
class Catalogue:
    experiments: dict[str, Experiment] = field(default_factory=dict)

    def add(self, e: Experiment) -> None:
        self.experiments[e.name] = e

    def get(self, name: str) -> Experiment:
        try:
            return self.experiments[name]
        except KeyError:
            raise KeyError(f"unknown experiment {name!r} (available: {', '.join(sorted(self.experiments))})") from None


CATALOGUE = Catalogue()
for _e in (SEED000, CATAPULT_GOAL, DECK_GOAL, CONSISTENCY_CATAPULT, CONSISTENCY_DECK):
    CATALOGUE.add(_e)
