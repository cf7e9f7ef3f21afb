"""The alignment filter's figures: the misalignment estimate with its ±3σ band (beside it, when
the bag has /truth/misalignment, the error with its ±3σ envelope), and every other state of
/alignment/state with its 1σ band, one panel per family of states (found by their labels)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..state_layout import ARCMIN_PER_RAD, display_unit, group_of
from . import style
from .series import Labelled, RunSeries

VALUE_ROWS = ('value', 'estimate', 'x')
MU_SIGMA_ROWS = ('mu_sigma', 'misalignment_sigma', 'misalignment_sigma_rad')


def misalignment_sigma(state: Labelled | None, t_s: np.ndarray) -> np.ndarray | None:
    """The misalignment's 1σ (N, 3) rad at the estimate's stamps t_s, from /alignment/state."""
    if state is None or not len(state.t_s):
        return None
    sig = next((state.rows[r][:, :3] for r in MU_SIGMA_ROWS if r in state.rows), None)
    if sig is None:
        idx = [i for i, n in enumerate(state.labels) if n.startswith('misalignment')]
        if len(idx) != 3 or 'sigma' not in state.rows:
            return None
        sig = state.rows['sigma'][:, idx]
    return np.column_stack([np.interp(t_s, state.t_s, sig[:, k], left=np.nan, right=np.nan) for k in range(3)])


def held(mu: np.ndarray) -> np.ndarray:
    """(K,) True where an estimate of the K (K, 3) repeats the one before it bit for bit: held, no
    match since (e.g. a beam that lost its reflector before the release); its time of validity is
    its last match's, which the bag does not give per output, so no error is drawn for it."""
    out = np.zeros(len(mu), dtype=bool)
    out[1:] = np.all(mu[1:] == mu[:-1], axis=1)
    return out


def misalignment(s: RunSeries, path: Path) -> Path | None:
    if s.misalignment is None:
        return None
    t, mu = s.misalignment
    mu_am = mu * ARCMIN_PER_RAD
    sig = misalignment_sigma(s.state, t)
    sig_am = None if sig is None else sig * ARCMIN_PER_RAD
    truth = s.truth_misalignment
    fresh = ~held(mu)
    fig, axs = style.figure(3, 2 if truth is not None else 1, 2.1)
    for k in range(3):
        ax = axs[k, 0]
        c = style.AXIS_COLORS[k]
        ax.plot(t, mu_am[:, k], color=c, lw=1.2, label='estimate')
        band = []
        if sig_am is not None:
            lo, hi = mu_am[:, k] - 3 * sig_am[:, k], mu_am[:, k] + 3 * sig_am[:, k]
            ax.fill_between(t, lo, hi, color=c, alpha=0.2, lw=0, label='±3σ')
            band = [lo, hi]
        tv = None
        if truth is not None:
            ax.plot(truth[0], truth[1][:, k] * ARCMIN_PER_RAD, 'k--', lw=1.0, label='truth')
            tv = np.interp(t, truth[0], truth[1][:, k] * ARCMIN_PER_RAD, left=np.nan, right=np.nan)
            tv = np.where(fresh, tv, np.nan)
        lim = style.limits([mu_am[:, k], tv, *band], t)
        if lim:
            ax.set_ylim(*lim)
        ax.set_ylabel(f'{style.AXIS_NAMES[k]}\n(arcmin)')
        if k == 0:
            ax.legend(loc='upper right', ncol=3)
            ax.set_title('estimate' + (' and truth' if truth is not None else ''))
        if truth is not None:
            assert tv is not None  # interpolated above whenever there is a truth
            _error_panel(axs[k, 1], t, mu_am[:, k], tv, sig_am, k)
    return style.finish(fig, axs, 'Misalignment (aircraft FLU axes)', path)


def _error_panel(ax, t: np.ndarray, mu_am: np.ndarray, truth_am: np.ndarray, sig_am: np.ndarray | None,
                 k: int) -> None:
    """Error (estimate - truth, where the truth is defined, on deck, and the estimate not held) and ±3σ."""
    err = mu_am - truth_am
    ax.plot(t, err, color=style.AXIS_COLORS[k], lw=1.2, label='error')
    band = []
    if sig_am is not None:
        on = np.isfinite(truth_am)
        env = np.where(on, 3 * sig_am[:, k], np.nan)
        ax.plot(t, env, 'k:', lw=1.0, label='±3σ')
        ax.plot(t, -env, 'k:', lw=1.0)
        band = [env, -env]
    ax.axhline(0.0, color='grey', lw=0.6)
    lim = style.limits([err, *band], t)
    if lim:
        ax.set_ylim(*lim)
    ax.set_ylabel('error (arcmin)')
    if k == 0:
        ax.legend(loc='upper right', ncol=2)
        ax.set_title('error (truth defined, estimate not held)')


def _rows(state: Labelled) -> tuple[str | None, str | None]:
    value = next((r for r in VALUE_ROWS if r in state.rows), None)
    if value is None:
        value = next((r for r in state.rows if r not in ('t_s', 'sigma', *MU_SIGMA_ROWS)), None)
    return value, 'sigma' if 'sigma' in state.rows else None


def _short(label: str, group: str) -> str:
    """A state's name within its panel: its axis ('eps_x' in 'eps': 'x')."""
    rest = label[len(group):].lstrip('_') if label.startswith(group) else label
    return rest.split('_')[0] or label


def states(s: RunSeries, path: Path) -> Path | None:
    st = s.state
    if st is None or not len(st.t_s):
        return None
    value_row, sigma_row = _rows(st)
    groups: dict[str, list[int]] = {}
    for i, label in enumerate(st.labels):
        groups.setdefault(group_of(label), []).append(i)
    names = list(groups)
    cols = 2 if len(names) > 1 else 1
    rows = (len(names) + cols - 1) // cols
    fig, axs = style.figure(rows, cols, 1.9)
    t = st.t_s
    for n, name in enumerate(names):
        ax = axs[n // cols, n % cols]
        unit, factor = display_unit(st.labels[groups[name][0]])
        vals = []
        for j, i in enumerate(groups[name]):
            c = f'C{j}'
            v = st.rows[value_row][:, i] * factor if value_row else np.zeros_like(t)
            ax.plot(t, v, color=c, lw=1.0, label=_short(st.labels[i], name) if len(groups[name]) > 1 else None)
            vals.append(v)
            if sigma_row:
                sg = st.rows[sigma_row][:, i] * factor
                ax.fill_between(t, v - sg, v + sg, color=c, alpha=0.18, lw=0)
                vals += [v - sg, v + sg]
        lim = style.limits(vals, t)
        if lim:
            ax.set_ylim(*lim)
        shown = name.replace('_', ' ')
        ax.set_ylabel(f'{shown} ({unit})' if unit else shown)
        if len(groups[name]) > 1:
            ax.legend(loc='best', ncol=len(groups[name]), fontsize=7)
    for n in range(len(names), rows * cols):
        axs[n // cols, n % cols].set_visible(False)
    what = 'value' if value_row is None else value_row
    return style.finish(fig, axs, f'/alignment/state: {what} with ±1σ', path)
