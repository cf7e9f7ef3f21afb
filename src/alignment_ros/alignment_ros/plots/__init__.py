"""Plots of a run drawn from its bag(s) (alignment_ros.plots.series reads them): the
misalignment estimate with ±3σ (and truth and error when recorded), the other estimated states
with 1σ, the NIS against its chi-square bounds with the consistency monitor's verdict, the
ship's motion and the aircraft's deck velocity, and air data. Each figure is drawn only when
its topics are in the bags; :func:`draw_all` returns what it drew. :func:`read_and_draw` draws
the ship-motion figure in a forked process meanwhile: its two 100 Hz streams are most of what a
run's bag takes to read."""
from __future__ import annotations

import logging
import os
import pickle
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

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


def read_and_draw(bags: list[Path], out: Path, topics: Iterable[str] | None = None,
                  scenario: dict | None = None) -> tuple[RunSeries, list[tuple[str, Path]]]:
    """`draw_all`'s figures (the same files; `scenario`: the run's, RunSeries.scenario), with
    the ship-motion figure read and drawn in a forked child while this process reads and draws
    the others; returns the series of every topic but the motion figure's (the report's text
    needs none of them) and [(title, png)]."""
    want = tuple(TOPICS if topics is None else topics)
    moving = tuple(t for t in want if t in MOTION_TOPICS)
    if not moving or not hasattr(os, 'fork'):
        s = read(bags, want)
        s.scenario = scenario
        return s, draw(s, out)
    Path(out).mkdir(parents=True, exist_ok=True)
    entry = next(f for f in FIGURES if f[0] == MOTION)
    child = _forked(lambda: entry[2](read(bags, moving), Path(out) / f'{MOTION}.png'))
    try:
        s = read(bags, tuple(t for t in want if t not in MOTION_TOPICS))
        s.scenario = scenario
        drawn = {name: path for name, _, path in _draw(s, out, skip=MOTION)}
    except BaseException:
        child(False)                               # this error, not the child's
        raise
    motion_png = child(True)
    return s, [(title, p) for name, title, _ in FIGURES
               if (p := motion_png if name == MOTION else drawn.get(name)) is not None]


def _draw(s: RunSeries, out: Path, skip: str | None = None) -> list[tuple[str, str, Path]]:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    drawn = []
    for name, title, fn in FIGURES:
        if name != skip and (path := fn(s, out / f'{name}.png')) is not None:
            drawn.append((name, title, path))
    return drawn


def _forked(fn: Callable[[], Any]) -> Callable[[], Any]:
    """Run fn in a forked child (its bag warnings silenced: this process logs them); return a
    function that waits for the child and returns fn's result, or (check) raises its error."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:                                   # the child: never returns
        os.close(r)
        status = 0
        try:
            logging.getLogger('alignment_ros').setLevel(logging.ERROR)
            payload = pickle.dumps((True, fn()))
        except BaseException as e:                 # noqa: BLE001 (told to the parent)
            payload, status = pickle.dumps((False, f'{type(e).__name__}: {e}')), 1
        with os.fdopen(w, 'wb') as f:
            f.write(payload)
        os._exit(status)
    os.close(w)

    def join(check: bool) -> Any:
        with os.fdopen(r, 'rb') as f:
            data = f.read()
        os.waitpid(pid, 0)
        ok, value = pickle.loads(data) if data else (False, 'the drawing process died')
        if not ok and check:
            raise RuntimeError(f'the {MOTION} figure: {value}')
        return value
    return join
