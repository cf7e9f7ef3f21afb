"""The speed goals' table, rendered from one `bench/speed.py --publish` run's output file
(bench/results/speed.json) into the README's and docs/speed.md's `<!-- results:speed -->` blocks,
stamped with the commit, date, machine load and command of the run that measured it.

    python bench/speed_table.py          (what `scripts/bench.sh speed --render` does)

A goal is met when every measurement of it in the run meets it: every graph run, each Monte Carlo
scenario in its own row (the engine's and the bare filter's figures are medians, best of the
run's repeats, as bench/speed.py measures them). A value is shown rounded toward its target's
wrong side, so a figure that reads as the target meets it. A goal the run did not measure is
listed as not measured."""
from __future__ import annotations

import json
import math
import re
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
RESULT = ROOT / 'bench' / 'results' / 'speed.json'
TARGETS = (ROOT / 'README.md', ROOT / 'docs' / 'speed.md')
BLOCK = re.compile(r'(<!-- results:speed -->\n)(.*?)(<!-- /results:speed -->)', re.S)

MC_RUNS_PER_MIN = 100.0          # 100 runs of a 300 s deck scenario in under a minute, two cores
ENGINE_US = 25.0                 # per IMU step with a 100 Hz master match, 15-state model
KF_RATIO = 3.0                   # x filterpy's speed on its own predict + update, n = 15, m = 3
GRAPH_RTF = 8.0                  # whole run, default scenario, --real-time-factor 0
STARTUP_S = 3.0                  # command to the first message recorded
MC_SCENARIOS = ('deck_paper', 'deck')   # the papers' parked deck and the carrier as it is


CODE_PATHS = ('src', 'bench', 'scripts', 'config', 'requirements.txt', 'requirements-bench.txt',
              ':!bench/results')
"""What the measured code is: a change to any of these (bench/results/ aside) marks the stamp."""


def code_version(root: Path = ROOT) -> str:
    """The commit measured: its short hash, '+changes' when the files of CODE_PATHS differ from it."""
    def git(*args: str) -> str:
        return subprocess.run(['git', *args], cwd=root, capture_output=True, text=True, check=True).stdout.strip()
    head = git('rev-parse', '--short', 'HEAD')
    dirty = git('status', '--porcelain', '--', *CODE_PATHS)
    return head + ('+changes' if dirty else '')


def _met(ok: bool) -> str:
    return 'met' if ok else 'not met'


def shown(value: float, digits: int, at_least: bool) -> str:
    """value with `digits` decimals, rounded down for an at-least target (up for an at-most one),
    so that a value that misses its target is never shown as one that meets it."""
    scale = 10.0 ** digits
    v = (math.floor if at_least else math.ceil)(value * scale) / scale
    return f'{v:.{digits}f}'


NOT_MEASURED = 'not measured in this run'


def _setting(value: Any) -> str:
    """A recorded argument as typed on a command line (a list: its items, space-separated)."""
    if isinstance(value, list):
        return ' '.join(str(v) for v in value)
    return f'{value:g}' if isinstance(value, float) else str(value)


def _list(values: list[float], fmt: Callable[[float], str]) -> str:
    return ', '.join(fmt(v) for v in values)


def rows(r: dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """(goal, target, measured, met) for every goal, those the run did not measure included."""
    out: list[tuple[str, str, str, str]] = []
    mc = r.get('mc', {})
    for sc in MC_SCENARIOS:
        goal, target = f'Monte Carlo, 300 s `{sc}`', f'>= {MC_RUNS_PER_MIN:g} runs/min'
        two, one = mc.get(sc, {}).get('2'), mc.get(sc, {}).get('1')
        if two is None:
            out.append((goal, target, NOT_MEASURED, NOT_MEASURED))
            continue
        runs = r.get('stamp', {}).get('settings', {}).get('runs')
        runs_2 = two.get('runs', runs)
        got = (f"{shown(two['runs_per_min'], 1, True)} runs/min on 2 workers ("
               + (f'{runs_2} runs, ' if runs_2 else '') + f"{two['cpu_s_per_run']:.1f} CPU s per run)")
        if one is not None:
            runs_1 = one.get('runs', runs)
            got += f", {one['runs_per_min']:.1f} on 1" + (f' ({runs_1} runs)' if runs_1 != runs_2 else '')
        out.append((goal, target, got, _met(two['runs_per_min'] >= MC_RUNS_PER_MIN)))
    goal, target = 'Engine, per IMU step with a 100 Hz master match (vm15 + KF, `deck_paper`)', f'<= {ENGINE_US:g} us'
    e = r.get('engine')
    out.append((goal, target, NOT_MEASURED, NOT_MEASURED) if e is None else
               (goal, target, f"{shown(e['median_us'], 0, False)} us median, {e['p95_us']:.0f} us p95",
                _met(e['median_us'] <= ENGINE_US)))
    goal, target = "Bare Kalman predict + update, n = 15, m = 3, against filterpy's", f'>= {KF_RATIO:g}x its speed'
    k = r.get('kf')
    if k is None:
        out.append((goal, target, NOT_MEASURED, NOT_MEASURED))
    else:
        ratio = k['filterpy_us'] / k['ours_us']
        out.append((goal, target, f"{k['ours_us']:.1f} us against {k['filterpy_us']:.1f} us: "
                                  f"{shown(ratio, 2, True)}x", _met(ratio >= KF_RATIO)))
    graphs = r.get('graphs', [])
    measured = bool(graphs) and all(g.get('startup_s') is not None and 'same_estimate' in g for g in graphs)
    graph_goals = [('Graph, default scenario at `--real-time-factor 0`: whole-run RTF', f'>= {GRAPH_RTF:g}x'),
                   ('Graph: first message after the command', f'< {STARTUP_S:g} s'),
                   ('Graph: messages lost', '0'),
                   ("Graph: the scored estimate, against the batch pipeline's on the same scenario", 'bit for bit')]
    if not measured:
        out += [(g, t, NOT_MEASURED, NOT_MEASURED) for g, t in graph_goals]
    else:
        rtf = [g['whole_run_rtf'] for g in graphs]
        start = [g['startup_s'] for g in graphs]
        lost = [g['lost'] for g in graphs]
        same = [bool(g['same_estimate']) for g in graphs]
        got = [_list(rtf, lambda v: shown(v, 2, True)) + f' ({len(graphs)} runs)',
               _list(start, lambda v: shown(v, 2, False) + ' s'), ', '.join(str(n) for n in lost),
               ', '.join('equal' if x else 'different' for x in same)]
        ok = [min(rtf) >= GRAPH_RTF, max(start) < STARTUP_S, max(lost) == 0, all(same)]
        out += [(g, t, m, _met(o)) for (g, t), m, o in zip(graph_goals, got, ok)]
    goal, target = 'Batch pipeline, peak RSS of a 1 h `deck` run', 'reported (the run is kept in memory)'
    mem = r.get('memory')
    out.append((goal, target, NOT_MEASURED, NOT_MEASURED) if mem is None else
               (goal, target, f"{mem['peak_1h_mib']:.0f} MiB (300 s: {mem['peak_300s_mib']:.0f} MiB; "
                              f"importing the pipeline alone: {mem['import_only_mib']:.0f} MiB); between the two "
                              f"runs it grows by {mem['per_hour_mib']:.0f} MiB per simulated hour", 'reported'))
    return out


def render(r: dict[str, Any]) -> str:
    """The block's markdown: the goals' table, the graph's CPU per process, the peers, the stamp."""
    lines = ['| goal | target | measured | |', '|---|---|---|---|']
    lines += [f'| {g} | {t} | {m} | {ok} |' for g, t, m, ok in rows(r)]
    graphs = r.get('graphs', [])
    if graphs:
        names = sorted({n for g in graphs for n, c in g['cpu_s'].items() if c is not None})
        per_min = {n: [60.0 * g['cpu_s'][n] / g['sim_time_s'] for g in graphs if g['cpu_s'].get(n) is not None]
                   for n in names}
        lines += ['', 'CPU seconds per simulated minute in the graph runs: '
                  + '; '.join(f'{n} {_list(v, lambda x: f"{x:.1f}")}' for n, v in per_min.items()) + '.']
    dds = r.get('dds')
    if dds and dds.get('runs'):
        share = [b['transport_cpu_s'] / b['graph_cpu_s'] for b in dds['runs']]
        lines += ['', f"The DDS transport alone, measured in the same run (bench/dds_cost.py: a publisher and "
                  f"its subscribers, each a process, taking the messages serialized): {dds['a_us']:.0f} us of "
                  f"CPU per message published plus {dds['b_us']:.0f} us per reader, and {dds['c_us']:.0f} us per "
                  f"message a reader takes; over the graph runs' messages and readers that is "
                  + _list([b['transport_cpu_s'] for b in dds['runs']], lambda x: f'{x:.1f}')
                  + " CPU s against the processes' (after their start-up) "
                  + _list([b['graph_cpu_s'] for b in dds['runs']], lambda x: f'{x:.1f}') + ' ('
                  + _list(share, lambda x: f'{100 * x:.0f} %') + '): the transport alone would allow '
                  + _list([b['rtf_bound'] for b in dds['runs']], lambda x: f'{x:.0f}x')
                  + ' real time on this machine.']
        odom = dds.get('read_us', {}).get('nav_msgs/msg/Odometry')
        if odom:
            lines[-1] += (f" Reading an Odometry from its bytes took {odom['rclpy_us']:.0f} us through rclpy's "
                          f"conversion and {odom['wire_us']:.0f} us through the nodes' reader (alignment_ros/wire.py).")
        failures, stopped = dds.get('failures') or [], dds.get('stopped_after_report') or 0
        if failures or stopped:
            lines[-1] += (f" In that benchmark {len(failures)} setting(s) failed and ran again"
                          + (f" ({'; '.join(failures)})" if failures else '')
                          + f", and {stopped} process(es) hung after reporting and were stopped.")
    peer = r.get('pyins')
    if peer and 'engine' in r:
        lines += ['', f"pyins' `run_feedback_filter` in the same run: {peer['pyins_us']:.0f} us per step, "
                  f"{peer['pyins_us'] / r['engine']['median_us']:.0f}x the engine's time."]
    s = r['stamp']
    settings = s.get('settings')
    lines += ['', f"Measured by `{s['command']}`"
              + (' (' + ', '.join(f'{k} {_setting(v)}' for k, v in settings.items()) + ')' if settings else '')
              + f" at commit `{s['commit']}`, {s['date']}, {s['cpus']} CPUs"
              + (f" ({s['cpu']})" if s.get('cpu') else '') + (f", {s['python']}" if s.get('python') else '')
              + f", load average {s['load_start']:.1f} "
              f"at the start and {s['load_end']:.1f} at the end; ratios are only meaningful within one run."]
    return '\n'.join(lines) + '\n'


def publish(r: dict[str, Any], targets: tuple[Path, ...] = TARGETS) -> list[Path]:
    """Replace the speed block of every target (each must have exactly one; nothing is written
    otherwise); the files written."""
    block = render(r)
    texts = {path: path.read_text() for path in targets}
    for path, text in texts.items():
        if len(BLOCK.findall(text)) != 1:
            raise ValueError(f'{path}: expected one <!-- results:speed --> ... <!-- /results:speed --> block')
    for path, text in texts.items():
        path.write_text(BLOCK.sub(lambda m: m.group(1) + block + m.group(3), text))
    return list(texts)


def main() -> int:
    done = publish(json.loads(RESULT.read_text()))
    print('wrote the speed block of ' + ', '.join(str(p.relative_to(ROOT)) for p in done))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
