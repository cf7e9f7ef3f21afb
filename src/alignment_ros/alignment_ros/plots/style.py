"""One look for every run plot: matplotlib's Agg backend (no display), figures 900 px wide (the
README's width) at 100 dpi, time in seconds on the x axis, units in every axis label."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

WIDTH_IN = 9.0
DPI = 100
AXIS_NAMES = ('x (roll)', 'y (pitch)', 'z (yaw)')
AXIS_COLORS = ('tab:blue', 'tab:orange', 'tab:green')
plt.rcParams.update({'font.size': 9, 'axes.titlesize': 10, 'legend.fontsize': 8, 'axes.grid': True,
                     'grid.alpha': 0.3})


def figure(rows: int, cols: int = 1, row_height_in: float = 2.0, sharex: bool = True):
    """(fig, axes[rows, cols]) of the house size."""
    fig, axs = plt.subplots(rows, cols, figsize=(WIDTH_IN, row_height_in * rows + 0.8), squeeze=False,
                            sharex=sharex)
    return fig, axs


def finish(fig, axs, title: str, path: Path, xlabel: str = 'simulation time (s)') -> Path:
    """Title, x labels on the bottom row, tight layout, save as PNG, close."""
    for col in range(axs.shape[1]):
        shown = [ax for ax in axs[:, col] if ax.get_visible()]
        if shown:
            shown[-1].set_xlabel(xlabel)
            shown[-1].xaxis.set_tick_params(labelbottom=True)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def note(ax, text: str) -> None:
    """A panel with nothing to draw says why."""
    ax.text(0.5, 0.5, text, ha='center', va='center', transform=ax.transAxes, color='grey')


def limits(values: list, t: np.ndarray, skip: float = 0.1) -> tuple[float, float] | None:
    """Y limits of the values (each (N,) over t, None skipped) after the first `skip` of the run:
    the prior's wide first seconds would flatten the rest."""
    late = t >= t[0] + skip * (t[-1] - t[0]) if len(t) else np.array([], bool)
    parts = [v[late] for v in values if v is not None and len(v) == len(t)]
    finite = np.concatenate([p[np.isfinite(p)] for p in parts]) if parts else np.array([])
    if not finite.size:
        return None
    lo, hi = float(finite.min()), float(finite.max())
    pad = max(0.08 * (hi - lo), 1e-3)
    return lo - pad, hi + pad
