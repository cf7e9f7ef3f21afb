"""The speed goals' table, rendered from one `bench/speed.py --publish` run's output file
(bench/results/speed.json) into the README's and docs/speed.md's `<!-- results:speed -->` blocks,
stamped with the commit, date, machine load and command of the run that measured it.

    python bench/speed_table.py          (what `scripts/bench.sh speed --render` does)

A goal is met when every measurement of it in the run meets it (the graph's runs, the Monte Carlo's
scenarios): the table never picks a run's best."""
from __future__ import annotations

import json
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


def code_version(root: Path = ROOT) -> str:
    """The commit measured: its short hash, '+changes' when src/ or bench/ differ from it."""
    def git(*args: str) -> str:
        return subprocess.run(['git', *args], cwd=root, capture_output=True, text=True, check=True).stdout.strip()
    head = git('rev-parse', '--short', 'HEAD')
    dirty = git('status', '--porcelain', '--', 'src', 'bench', 'scripts')
    return head + ('+changes' if dirty else '')


def _met(ok: bool) -> str:
    return 'met' if ok else 'not met'


def _list(values: list[float], fmt: Callable[[float], str]) -> str:
    return ', '.join(fmt(v) for v in values)


def rows(r: dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """(goal, target, measured, met) for every goal the run measured."""
    out: list[tuple[str, str, str, str]] = []
    for sc, by_workers in r.get('mc', {}).items():
        two, one = by_workers.get('2'), by_workers.get('1')
        if two is None:
            continue
        got = f"{two['runs_per_min']:.1f} runs/min on 2 workers ({two['cpu_s_per_run']:.1f} CPU s per run)"
        if one is not None:
            got += f", {one['runs_per_min']:.1f} on 1"
        out.append((f'Monte Carlo, 300 s `{sc}`', f'>= {MC_RUNS_PER_MIN:g} runs/min', got,
                    _met(two['runs_per_min'] >= MC_RUNS_PER_MIN)))
    if 'engine' in r:
        e = r['engine']
        out.append(('Engine, per IMU step with a 100 Hz master match (vm15 + KF, `deck_paper`)', f'<= {ENGINE_US:g} us',
                    f"{e['median_us']:.0f} us median, {e['p95_us']:.0f} us p95", _met(e['median_us'] <= ENGINE_US)))
    if 'kf' in r:
        k = r['kf']
        ratio = k['filterpy_us'] / k['ours_us']
        out.append(("Bare Kalman predict + update, n = 15, m = 3, against filterpy's", f">= {KF_RATIO:g}x its speed",
                    f"{k['ours_us']:.1f} us against {k['filterpy_us']:.1f} us: {ratio:.2f}x", _met(ratio >= KF_RATIO)))
    graphs = r.get('graphs', [])
    if graphs:
        rtf = [g['whole_run_rtf'] for g in graphs]
        start = [g['startup_s'] for g in graphs]
        lost = [g['lost'] for g in graphs]
        out.append(('Graph, default scenario at `--real-time-factor 0`: whole-run RTF', f'>= {GRAPH_RTF:g}x',
                    _list(rtf, lambda v: f'{v:.2f}') + f' ({len(graphs)} runs)', _met(min(rtf) >= GRAPH_RTF)))
        out.append(('Graph: first message after the command', f'< {STARTUP_S:g} s',
                    _list(start, lambda v: f'{v:.2f} s'), _met(max(start) < STARTUP_S)))
        out.append(('Graph: messages lost', '0', _list([float(x) for x in lost], lambda v: f'{v:.0f}'),
                    _met(max(lost) == 0)))
        if all('same_estimate' in g for g in graphs):
            same = [bool(g['same_estimate']) for g in graphs]
            out.append(("Graph: the scored estimate, against the batch pipeline's on the same scenario", 'bit for bit',
                        ', '.join('equal' if x else 'different' for x in same), _met(all(same))))
    mem = r.get('memory')
    if mem:
        out.append(('Batch pipeline, peak RSS of a 1 h `deck` run', 'reported and bounded',
                    f"{mem['peak_1h_mib']:.0f} MiB; ~ {mem['base_mib']:.0f} MiB + {mem['per_hour_mib']:.0f} MiB "
                    'per simulated hour', 'reported'))
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
    peer = r.get('pyins')
    if peer and 'engine' in r:
        lines += ['', f"pyins' `run_feedback_filter` in the same run: {peer['pyins_us']:.0f} us per step, "
                  f"{peer['pyins_us'] / r['engine']['median_us']:.0f}x the engine's time."]
    s = r['stamp']
    lines += ['', f"Measured by `{s['command']}` at commit `{s['commit']}`, {s['date']}, {s['cpus']} CPUs, "
              f"load average {s['load_start']:.1f} at the start and {s['load_end']:.1f} at the end; "
              'ratios are only meaningful within one run.']
    return '\n'.join(lines) + '\n'


def publish(r: dict[str, Any], targets: tuple[Path, ...] = TARGETS) -> list[Path]:
    """Replace the speed block of each target file that has one; the files written."""
    block = render(r)
    done = []
    for path in targets:
        text = path.read_text()
        new = BLOCK.sub(lambda m: m.group(1) + block + m.group(3), text)
        if new != text or BLOCK.search(text):
            path.write_text(new)
            done.append(path)
    return done


def main() -> int:
    done = publish(json.loads(RESULT.read_text()))
    print('wrote the speed block of ' + ', '.join(str(p.relative_to(ROOT)) for p in done))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
