"""Plots of a run drawn from its bag(s) (alignment_ros.plots.series reads them): the
misalignment estimate with ±3σ (and truth and error when recorded), the other estimated states
with 1σ, the NIS against its chi-square bounds with the consistency monitor's verdict, the
ship's motion and the aircraft's deck velocity, and air data. Each figure is drawn only when
its topics are in the bags; :func:`draw_all` returns what it drew. :func:`read_and_draw` draws
the ship-motion figure in a process of its own meanwhile: its two 100 Hz streams are most of
what a run's bag takes to read."""
from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path

from .. import topics as topic_names
from . import air_data as air
from . import alignment, consistency, motion
from .series import TOPICS, RunSeries, read

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
    """Every figure `s` allows into `out`; [(title, png)]."""
    return [(title, path) for _, title, path in _draw(s, out)]


MOTION = 'motion'
MOTION_TOPICS = (topic_names.SHIP_ODOM, topic_names.LDV_TWIST)
"""The ship-motion figure's topics (and no other figure's)."""
MOTION_TIMEOUT_S = 300.0
"""How long read_and_draw waits for the motion figure's process once its own figures are done."""


def read_and_draw(bags: list[Path], out: Path, topics: Iterable[str] | None = None,
                  scenario: dict | None = None) -> tuple[RunSeries, list[tuple[str, Path]]]:
    """`draw_all`'s figures (the same files; `scenario`: the run's, RunSeries.scenario), with
    the ship-motion figure read and drawn by a process of its own (`motion_process.py`, a new
    interpreter: the launchers that call this run DDS threads, so they do not fork) while this
    one reads and draws the others; returns the series of every topic but the motion figure's
    (the report's text needs none of them) and [(title, png)]. An error in either process is
    raised here (this one's first; the other process is then stopped)."""
    want = tuple(TOPICS if topics is None else topics)
    moving = tuple(t for t in want if t in MOTION_TOPICS)
    if not moving:
        s = read(bags, want)
        s.scenario = scenario
        return s, draw(s, out)
    Path(out).mkdir(parents=True, exist_ok=True)
    child = subprocess.Popen([sys.executable, '-m', 'alignment_ros.plots.motion_process',
                              str(Path(out) / f'{MOTION}.png'), *(str(b) for b in bags)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        s = read(bags, tuple(t for t in want if t not in MOTION_TOPICS))
        s.scenario = scenario
        drawn: dict[str, Path | None] = {name: path for name, _, path in _draw(s, out, skip=MOTION)}
        said, err = child.communicate(timeout=MOTION_TIMEOUT_S)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    if child.returncode != 0:
        lines = err.strip().splitlines()
        raise RuntimeError(f"the {MOTION} figure: {lines[-1] if lines else f'exit status {child.returncode}'}")
    drawn[MOTION] = Path(said.strip()) if said.strip() else None
    return s, [(title, p) for name, title, _ in FIGURES if (p := drawn.get(name)) is not None]


def _draw(s: RunSeries, out: Path, skip: str | None = None) -> list[tuple[str, str, Path]]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    drawn = []
    for name, title, fn in FIGURES:
        if name != skip and (path := fn(s, out / f'{name}.png')) is not None:
            drawn.append((name, title, path))
    return drawn
