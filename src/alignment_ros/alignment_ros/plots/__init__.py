"""Plots of a run drawn from its bag(s) (alignment_ros.plots.series reads them): the
misalignment estimate with ±3σ (and truth and error when recorded), the other estimated states
with 1σ, the NIS against its chi-square bounds with the consistency monitor's verdict, the
ship's motion and the aircraft's deck velocity, and air data. Each figure is drawn only when
its topics are in the bags; :func:`draw_all` returns what it drew."""
from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from . import air_data as air
from . import alignment, consistency, motion
from .series import RunSeries, read

FIGURES = (
    ('misalignment', 'Misalignment estimate', alignment.misalignment),
    ('states', 'Estimated states', alignment.states),
    ('consistency', 'Innovation consistency (NIS)', consistency.nis),
    ('motion', "Ship motion and the aircraft's deck velocity", motion.motion),
    ('air_data', 'Air data', air.air_data),
)


def draw_all(bags: Iterable[Path], out: Path, topics: Iterable[str] | None = None
             ) -> list[tuple[str, Path]]:
    """Read the bags and draw every figure their topics allow into `out`; [(title, png)]."""
    s = read([Path(b) for b in bags], topics)
    return draw(s, out)


def draw(s: RunSeries, out: Path) -> list[tuple[str, Path]]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    drawn = []
    for name, title, fn in FIGURES:
        path = fn(s, out / f'{name}.png')
        if path is not None:
            drawn.append((title, path))
    return drawn
