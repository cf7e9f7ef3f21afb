"""What an experiment is: data. A base scenario, a list of cells (one sweep point each: its table
values and the dotted scenario overrides that realise it), the score time, settling
thresholds, and reference rows. `quick` shrinks it (fewer seeds and cells, shorter runs)
for the tests without changing what is computed. The named experiments: catalogue.py."""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

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
    stat: str = 'rms'                 # ours to compare with: 'rms' error or mean 'sigma'


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
    quantity: str = 'misalignment'   # or 'attitude' (slave INS attitude error, nav frame E/N/U)
    axes: tuple[str, str, str] = AXES
    notes: str = ''                  # our reading of the differences, printed in the report

    def specs(self, seeds: int | None = None, first_seed: int = 1) -> list[RunSpec]:
        """Every (cell, seed) run; seed numbers are first_seed .. first_seed + seeds - 1 in every cell,
        so cells are compared on the same random draws."""
        n = self.seeds if seeds is None else seeds
        out: list[RunSpec] = []
        for cell, i in itertools.product(self.cells, range(n)):
            out.append(RunSpec(index=len(out), cell=cell.label, scenario=self.scenario,
                               overrides=self.base + cell.overrides, seed=first_seed + i,
                               score_at=self.score_at, settle_arcmin=self.settle_arcmin, values=cell.values,
                               quantity=self.quantity))
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
