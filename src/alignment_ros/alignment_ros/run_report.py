"""A run's pictures and report.md, beside its summary.json: the plots of its bag(s)
(:mod:`alignment_ros.plots`, into plots/) and a page that puts together the result table (from
summary.json), the last estimate the bag holds (with or without truth), the diagnostics summary
(rejections by reason, gaps, health, the consistency monitor) and the plots. Written by
run_graph.sh and replay.sh after every run, and by plot_bag.sh for any bag."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import yaml

from . import air_data_summary, plots
from .plots.alignment import misalignment_sigma
from .plots.consistency import verdict
from .plots.series import RunSeries
from .state_layout import ARCMIN_PER_RAD, display_unit

AXES = ('x (roll)', 'y (pitch)', 'z (yaw)')
COUNTER_KEYS = ('updates', 'gated', 'imu', 'master', 'ldv', 'doppler', 'imu_gaps', 'bridged_gaps',
                'gate_released', 'quaternion_normalised', 'launch_not_felt', 'unmatched_master',
                'numerical_failures', 'consistency_failures', 'nis_windows', 'nis_windows_failed')
LEVELS = ('OK', 'WARN', 'ERROR', 'STALE')


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ['| ' + ' | '.join(header) + ' |', '|' + '|'.join('---' for _ in header) + '|',
            *('| ' + ' | '.join(r) + ' |' for r in rows)]


def result_table(s: dict) -> list[str]:
    """The summary's misalignment score (arcmin, 3 decimals as the printed table); without truth
    the estimate and its 1σ when the summary gives them (``truth: false``), or why none."""
    if s.get('truth') is False and s.get('misalignment_estimate_rad') is not None:
        est, sig = s['misalignment_estimate_rad'], s['misalignment_sigma_rad']
        rows = [[AXES[k], f'{est[k] * ARCMIN_PER_RAD:.3f}', f'{sig[k] * ARCMIN_PER_RAD:.3f}'] for k in range(3)]
        return [f"No truth in the input: the misalignment estimate and its 1σ at t = {s['estimate_stamp_s']:.2f} s, "
                'aircraft FLU axes, arcmin:', '', *_table(['axis', 'estimate', '1σ'], rows)]
    if s.get('misalignment_truth_rad') is None:
        return ['No misalignment score (no /truth/misalignment to score against).']
    mu, est = np.array(s['misalignment_truth_rad']), np.array(s['misalignment_estimate_rad'])
    sig = np.array(s['misalignment_sigma_rad'])
    rows = [[AXES[k], f'{mu[k] * ARCMIN_PER_RAD:.3f}', f'{est[k] * ARCMIN_PER_RAD:.3f}',
             f'{(est[k] - mu[k]) * ARCMIN_PER_RAD:.3f}', f'{sig[k] * ARCMIN_PER_RAD:.3f}'] for k in range(3)]
    head = f"Misalignment at t = {s['scored_at_s']:.2f} s (the end of deck matching)"
    if s.get('misalignment_valid_s') is not None:
        head += (f", the estimate held since its last match (valid at t = {s['misalignment_valid_s']:.2f} s, "
                 "the truth taken there)")
    out = [head + ', aircraft FLU axes, arcmin:', '', *_table(['axis', 'truth', 'estimate', 'error', '1σ'], rows)]
    if s.get('attitude_error_rad') is not None:
        err, sig = np.array(s['attitude_error_rad']), np.array(s['attitude_sigma_rad'])
        out += ['', f"The slave INS's attitude error at t = {s['attitude_stamp_s']:.2f} s (what the aircraft "
                "carries away), nav frame, arcmin:", '',
                *_table(['axis', 'error', '1σ'], [[name, f'{err[k] * ARCMIN_PER_RAD:.3f}',
                                                   f'{sig[k] * ARCMIN_PER_RAD:.3f}']
                                                  for k, name in enumerate(('east', 'north', 'up'))])]
    return out


def whole_estimate(s: dict) -> list[str]:
    """The summary's whole estimate (``state_estimate``: every state by its unit-labelled name),
    each in the unit the plots use."""
    st = s.get('state_estimate')
    if not st:
        return []
    rows = []
    for name, v, sg in zip(st['labels'], st['estimate'], st['sigma']):
        unit, f = display_unit(name)
        rows.append([name, f'{v * f:.4g}', f'{sg * f:.4g}', unit or '-'])
    return [f"The whole estimate at t = {st['t_s']:.2f} s:", '', *_table(['state', 'estimate', '1σ', 'unit'], rows)]


def whiteness_lines(s: dict) -> list[str]:
    w = s.get('innovation_whiteness')
    if 'innovation_whiteness' not in s:
        return []
    if not w:
        return ['- innovation whiteness: no window completed']
    return [f"- innovation whiteness: {w['result']} (last window: Ljung-Box p {w['p']:.3g}, lag-1 "
            f"autocorrelation up to {w['r1_max']:.3f} against ±{w['band']:.3f}; {w['windows_failed']} of "
            f"{w['windows']} windows failed); relative velocity: {w['relative_velocity']}"]


def air_table(s: dict) -> list[str]:
    a = s.get('air_data')
    if not a:
        return []
    if not a.get('paired'):
        return [f"Air data: {a.get('estimates', 0)} estimates, none paired with a truth."]
    rows = []
    for n, scale, unit in air_data_summary.SHOWN:
        rms = a['rms'][n]
        e, sig = a['last'][n]
        name = n.replace('_rad', '').replace('_mps', '') + (f' ({unit})' if unit else '')
        rows.append([name, '-' if rms is None else f'{rms * scale:.4g}', f'{e * scale:.4g}', f'{sig * scale:.4g}'])
    return [f"Air data: {a['paired']} estimates paired with the truth; RMS after the first "
            f"{air_data_summary.SETTLE_S:.0f} s, error and 1σ at t = {a['t_last_s']:.2f} s:", '',
            *_table(['quantity', 'RMS', 'error', '1σ'], rows)]


def last_estimate(series: RunSeries) -> list[str]:
    """The bag's last misalignment estimate and 1σ (what a run without truth ends with)."""
    if series.misalignment is None:
        return []
    t, mu = series.misalignment
    sig = misalignment_sigma(series.state, t[-1:])
    rows = [[AXES[k], f'{mu[-1, k] * ARCMIN_PER_RAD:.3f}',
             '-' if sig is None or not np.isfinite(sig[0, k]) else f'{sig[0, k] * ARCMIN_PER_RAD:.3f}']
            for k in range(3)]
    return [f'Last estimate in the bag, t = {t[-1]:.2f} s (arcmin):', '', *_table(['axis', 'estimate', '1σ'], rows)]


def run_lines(s: dict) -> list[str]:
    rtf = s.get('real_time_factor')
    out = [f"- simulated {s.get('sim_time_s', 0):.2f} s of {s.get('planned_sim_time_s', s.get('sim_time_s', 0)):.2f} s"
           f" in {s.get('wall_time_s', 0):.2f} s wall" + (f' (real-time factor {rtf:.2f})' if rtf else ''),
           f"- messages lost: {s.get('lost_total')}, foreign: {s.get('foreign_total', 0)}",
           '- complete: yes' if s.get('complete') else
           '- **INCOMPLETE**: ' + '; '.join(s.get('problems') or ['unknown'])]
    if s.get('replayed_from'):
        out.append(f"- replayed from `{s['replayed_from']}`")
    return out


def diagnostics_lines(series: RunSeries) -> list[str]:
    """Per diagnostics status: final level and message, health, rejections by reason, gaps,
    counters, and how long it spent in each level."""
    out: list[str] = []
    for name, d in series.diagnostics.items():
        last = d.values[-1] if d.values else {}
        out += [f'**{name}**: {verdict(d)}; last message: "{d.messages[-1] if d.messages else ""}"', '']
        rejected = {k[len('rejected_'):]: v for k, v in last.items()
                    if k.startswith('rejected_') and v not in ('0', '')}
        out.append('- rejections by reason: ' + (', '.join(f'{k} {v}' for k, v in sorted(rejected.items()))
                                                  if rejected else 'none'))
        counters = [f'{k} {last[k]}' for k in COUNTER_KEYS if k in last]
        if counters:
            out.append('- counters: ' + ', '.join(counters))
        for key, what in (('silent', 'silent streams'), ('flags', 'flags'), ('excluded_ports', 'excluded ports')):
            if last.get(key):
                out.append(f'- {what}: {last[key]}')
        levels = [int(v) for v in d.levels]
        seen = ', '.join(f'{LEVELS[min(lv, 3)]} {levels.count(lv)}' for lv in sorted(set(levels)))
        out.append(f'- messages per level: {seen}')
        for lv in sorted({lv for lv in levels if lv > 0}):
            at = [i for i, x in enumerate(levels) if x == lv]
            texts = sorted({d.messages[i] for i in at})
            out.append(f'- {LEVELS[min(lv, 3)]} from t = {d.t_s[at[0]]:.2f} s to {d.t_s[at[-1]]:.2f} s: '
                       + '; '.join(f'"{x}"' for x in texts[:5]) + (' ...' if len(texts) > 5 else ''))
        out += [f"- healthy at the end: {last.get('healthy', '?')}", '']
    return out or ['No /diagnostics in the bag.']


def markdown(title: str, s: dict | None, series: RunSeries, drawn: list[tuple[str, Path]], base: Path) -> str:
    lines = [f'# {title}', '']
    if s is not None:
        lines += ['## Result', '', *result_table(s), '']
        air = air_table(s)
        if air:
            lines += [*air, '']
        lines += [*run_lines(s), *whiteness_lines(s), '']
        whole = whole_estimate(s)
        if whole:
            lines += [*whole, '']
    est = last_estimate(series)
    if est:
        lines += [*est, '']
    lines += ['## Diagnostics', '', *diagnostics_lines(series), '## Plots', '']
    for t, p in drawn:
        lines += [f'### {t}', '', f'![{t}]({Path(os.path.relpath(p, base)).as_posix()})', '']
    return '\n'.join(lines)


def scenario_next_to(*paths: Path | None) -> dict | None:
    for p in paths:
        if p is not None and (Path(p).parent / 'scenario.yaml').exists():
            return yaml.safe_load((Path(p).parent / 'scenario.yaml').read_text())
    return None


def build(bags: list[Path | None], out: Path, s: dict | None, title: str, topics=None,
          report_dir: Path | None = None) -> Path:
    """Draw the bags' plots into out/plots (or out itself when report_dir is given as out) and
    write report.md into report_dir (default out); return its path. A None bag (e.g. no input
    bag) is skipped."""
    report_dir = report_dir or out
    series, drawn = plots.read_and_draw([b for b in bags if b is not None], out, topics, scenario_next_to(*bags))
    path = Path(report_dir) / 'report.md'
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(markdown(title, s, series, drawn, Path(report_dir)) + '\n')
    return path


def write(run_dir: Path, s: dict | None, input_bag: Path | None = None) -> Path | None:
    """The run's plots/ and report.md (a failure to draw says so on stderr and never changes
    the run's result)."""
    run_dir = Path(run_dir)
    name = (s or {}).get('scenario') or ('replay' if input_bag else run_dir.name)
    try:
        return build([run_dir / 'bag', input_bag], run_dir / 'plots', s, f'Run {run_dir.name}: {name}',
                     report_dir=run_dir)
    except Exception as e:     # noqa: BLE001 (the run's numbers are written already)
        print(f'{run_dir}: no plots or report.md: {type(e).__name__}: {e}', file=sys.stderr)
        return None
