"""Peak memory of the batch pipeline against the simulated duration: the `deck` scenario (seed 1)
simulated and aligned (`pipeline.simulate` then `pipeline.align`, the work of `pipeline.run(sc,
keep_truth=False)` and of a Monte Carlo run) in a fresh child process per duration, so each peak
is that run's alone; a child that only imports the pipeline gives the interpreter + libraries.

    scripts/bench.sh batch_memory [--durations 300 900 3600] [--trace]

Per duration: the wall time of simulate + align, the child's peak RSS (its own ru_maxrss; the
parent's os.wait4 rusage of the child agrees), the peak less the import-only child's, the peak
per simulated hour, the RSS after simulate and after align, and what the run holds at its end (a
walk of the Inputs and of the filter's attributes: numpy buffers once, long lists extrapolated
from evenly spaced elements). A least-squares line through (duration, peak) gives the growth in
MiB per simulated hour. --trace: one more child at the shortest duration under tracemalloc: the
ship synthesis' peak and its ShipSample list (simulate builds it and drops it), the top allocation
sites near simulate's traced peak (with the call stack there), of what simulate leaves (the
inputs) and of what align adds (the estimates).

Why: the batch pipeline keeps the whole run in memory by design (the filter is fed from lists of
every sample, and the engine is built with keep_history=True, so every estimate is kept); this
states how much, so a long run's memory can be planned and a change that makes it worse shows.

Measured 2026-12-03 on this 2-core machine (load average 0-0.8; `deck`, the carrier as it is;
durations 300, 900, 3600 s; the kernels' cache warm): peak RSS 306.4, 545.1, 1625.9 MiB (wall 7,
20, 89 s; the import-only child 67 MiB): peak ~ 186 MiB + 1440 MiB per simulated hour (largest
residual 0.7 MiB; about 4 kB per 100 Hz sample), because every sample of the whole run is held in
memory. The bound: peak ~ base + k x duration, base ~ 190 MiB, k ~ 1.44 GiB per simulated hour.
The base holds the interpreter and libraries (67 MiB) and, since the landing gear's loop became a
compiled kernel, numba (+56 MiB imported, +58 MiB once its first kernel is loaded: LLVM), now
resident while simulate builds the inputs: the code before (`e8e4944`, numba imported only by the
filter's kernels in align) gave 277.6, 449.2, 1534.6 MiB in the same session, peak ~ 134 MiB +
1395 MiB/h. The peak is reached inside simulate, not at the end (earlier tracemalloc runs put it
in SlaveImuStage.run_batch: AircraftKinematics.increments_batch / _on_deck, about ten rotation
temporaries of 216 B per sample each, 27 float64, and einsum workspace, on top of the inputs made
so far; the ship synthesis adds a fixed ~45 MiB workspace). What the run keeps after align (631
MiB per simulated hour by the walk; RSS after align ~ 222 + 789 MiB/h, the rest presumably freed
heap not handed back): per-sample Python records with small numpy arrays: LDV 132, IMU 126,
estimates 122 (3.5 kB each, 10 Hz), master 114 MiB/h (368-664 B per sample for 48-104 B of
numbers); the arrays: ship batch 55, aircraft truth 36, sensor truth 29, the filter's LDV history
16.5 MiB/h.

Measured 2026-12-04 (load average below 1; durations 300 and 1800 s): the code above gave peak ~
189 MiB + 1427 MiB per simulated hour, reached inside simulate. Since then the slave IMU's synthesis
and align's decoding of the LDV stream run 6000 samples (60 s) at a time (`pipeline.BATCH_SAMPLES`,
the same numbers bit for bit): peak ~ 206 MiB + 838 MiB/h, reached in align at both durations, where
the RSS after align is ~ 206 + 839 MiB/h; the 1800 s run's peak 624.8 against 902.9 MiB, its wall
time 42.4 against 50.6 s (simulate 9.2 against 13.2 s).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
import tracemalloc
import types
from collections import deque
from pathlib import Path

import numpy as np

MIB = 2.0 ** 20
SAMPLE = 64                 # elements of a long list or tuple walked (the rest extrapolated)
SKIP = (type, types.ModuleType, types.FunctionType, types.BuiltinFunctionType, types.MethodType)


# ----- the child -----

def rss_mib() -> float:
    for line in Path('/proc/self/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0
    return float('nan')


def peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0      # KiB on Linux


def children(o: object) -> list[object]:
    """What o references: a container's items, an instance's __dict__ and __slots__ values."""
    if isinstance(o, dict):
        return [*o.keys(), *o.values()]
    if isinstance(o, (list, tuple, set, frozenset, deque)):
        return list(o)
    out: list[object] = []
    d = getattr(o, '__dict__', None)
    if isinstance(d, dict):
        out.append(d)
    for cls in type(o).__mro__:
        for name in getattr(cls, '__slots__', ()):
            if name not in ('__dict__', '__weakref__') and hasattr(o, name):
                out.append(getattr(o, name))
    return out


def deep_bytes(obj: object, seen: set[int]) -> float:
    """Bytes held by obj and what it references that is not yet in `seen`. A numpy array counts its
    own buffer (a view: its header, then its base once, unweighted: one buffer under many views);
    a list or tuple longer than SAMPLE is walked on SAMPLE evenly spaced elements, weighted up."""
    total = 0.0
    stack: list[tuple[object, float]] = [(obj, 1.0)]
    while stack:
        o, w = stack.pop()
        if id(o) in seen or isinstance(o, SKIP):
            continue
        seen.add(id(o))
        total += w * sys.getsizeof(o)
        if isinstance(o, np.ndarray):
            if isinstance(o.base, np.ndarray):
                stack.append((o.base, 1.0))
            continue
        items = children(o)
        if isinstance(o, (list, tuple)) and len(items) > SAMPLE:
            idx = np.linspace(0, len(items) - 1, SAMPLE).round().astype(int)
            w *= len(items) / SAMPLE
            items = [items[i] for i in idx]
        stack.extend((x, w) for x in items)
    return total


def holdings(inp: object, filt: object) -> dict[str, tuple[float, int]]:
    """Bytes and items (a list's or tuple's length, else 0) of each field of the Inputs and each
    attribute of the filter, in that order (what an earlier one holds is not counted again)."""
    seen: set[int] = set()
    attrs = {f'inputs.{k}': v for k, v in vars(inp).items()}
    rest = dict(vars(filt))
    attrs.update({f'filter.{k}': rest.pop(k) for k in ('_outputs', '_published')})
    attrs.update({f'filter.{k}': v for k, v in rest.items()})
    return {k: (deep_bytes(v, seen), len(v) if isinstance(v, (list, tuple)) else 0) for k, v in attrs.items()}


def top_sites(stats: list, n: int) -> list[str]:
    """One line per site: file (from the package on) and line, size, blocks (and the change)."""
    out = []
    for s in stats[:n]:
        where = s.traceback[0].filename.split('alignment_core/alignment_core/')[-1].split('site-packages/')[-1]
        diff = f'  ({s.size_diff / MIB:+.2f})' if hasattr(s, 'size_diff') else ''
        out.append(f'{where + ":" + str(s.traceback[0].lineno):32s} {s.size / MIB:8.2f} MiB {s.count:9d} blocks{diff}')
    return out


class PeakCatcher:
    """A profile hook (sys.setprofile) that, at every function return, snapshots tracemalloc when
    the traced memory has grown PEAK_STEP past the last snapshot: the last snapshot is taken within
    that step of the largest traced size seen at a return, with the call stack it was taken in."""
    PEAK_STEP = 1.05

    def __init__(self) -> None:
        self.size = 0
        self.snapshot: tracemalloc.Snapshot | None = None
        self.stack = ''

    def __call__(self, frame: types.FrameType, event: str, arg: object) -> None:
        if event not in ('return', 'c_return'):
            return
        now = tracemalloc.get_traced_memory()[0]
        if now > self.size * self.PEAK_STEP:
            self.size, self.snapshot = now, tracemalloc.take_snapshot()
            names = []
            f: types.FrameType | None = frame
            while f is not None and f.f_code.co_name != 'child':
                names.append(f.f_code.co_qualname)
                f = f.f_back
            self.stack = ' < '.join(names) + (f' (returning from {getattr(arg, "__name__", "?")})'
                                              if event == 'c_return' else '')


def child(duration_s: float, trace: bool) -> dict:
    """Import the pipeline; with duration_s > 0 simulate and align the deck scenario for that long."""
    from alignment_core import pipeline
    from alignment_core.config import scenario
    out: dict = {'import_rss_mib': rss_mib(), 'import_peak_mib': peak_mib()}
    if duration_s <= 0:
        return out
    sc = scenario.load('deck', {'duration_s': duration_s}, seed=1)
    lines: list[str] = []
    catcher = PeakCatcher()
    if trace:
        tracemalloc.start(1)
        ships = pipeline.ship_samples(sc)
        now, peak = tracemalloc.get_traced_memory()
        lines.append(f'ship truth (pipeline.ship_samples, simulate\'s first step): {peak / MIB:.1f} MiB at its peak; '
                     f'its ShipSample list (stacked into a ShipBatch, then dropped) {now / MIB:.1f} MiB '
                     f'for {len(ships)} samples')
        del ships
        tracemalloc.reset_peak()
        sys.setprofile(catcher)
    t = time.perf_counter()
    inp = pipeline.simulate(sc)
    sys.setprofile(None)
    out.update(simulate_s=time.perf_counter() - t, simulate_rss_mib=rss_mib(), simulate_peak_mib=peak_mib())
    if trace:
        now, peak = tracemalloc.get_traced_memory()
        lines.append(f'simulate: traced {now / MIB:.1f} MiB held after, {peak / MIB:.1f} MiB at its peak')
        if catcher.snapshot is not None:
            lines.append(f'  near the peak ({catcher.size / MIB:.1f} MiB traced) in {catcher.stack}; top sites:')
            lines += ['    ' + x for x in top_sites(catcher.snapshot.statistics('lineno'), 10)]
        s1 = tracemalloc.take_snapshot()
        lines.append('  top sites held after simulate:')
        lines += ['    ' + x for x in top_sites(s1.statistics('lineno'), 10)]
    t = time.perf_counter()
    filt = pipeline.align(sc, inp)
    out.update(align_s=time.perf_counter() - t, align_rss_mib=rss_mib(), align_peak_mib=peak_mib())
    if trace:
        now, peak = tracemalloc.get_traced_memory()
        lines.append(f'align: traced {now / MIB:.1f} MiB held after, {peak / MIB:.1f} MiB at the peak; '
                     'top sites added:')
        lines += ['    ' + x for x in top_sites(tracemalloc.take_snapshot().compare_to(s1, 'lineno'), 10)]
        tracemalloc.stop()
    out.update(samples=len(inp.ships), imu=len(inp.imu), master=len(inp.master), ldv=len(inp.ldv),
               estimates=len(filt.outputs), trace=lines)
    if not trace:
        out['holdings'] = holdings(inp, filt)
    return out


# ----- the driver -----

def run_child(duration_s: float, trace: bool = False) -> dict:
    """One child; its own report plus the wall time and ru_maxrss the parent sees (os.wait4)."""
    args = [sys.executable, __file__, '--child', str(duration_s)] + (['--trace'] if trace else [])
    t = time.perf_counter()
    p = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
    assert p.stdout is not None
    text = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise RuntimeError(f'child for {duration_s:g} s exited {p.returncode}')
    out = json.loads(text.strip().splitlines()[-1])
    out.update(child_wall_s=time.perf_counter() - t, child_maxrss_mib=ru.ru_maxrss / 1024.0)
    return out


def summary(holds: dict[str, list], hours: float, held_mib: float) -> list[str]:
    """The holdings from 1 % of their sum up, largest first, with MiB per simulated hour and bytes
    per item of a list."""
    total = sum(v for v, _ in holds.values())
    rows = sorted(holds.items(), key=lambda kv: -kv[1][0])
    big = [(k, v, n) for k, (v, n) in rows if v >= 0.01 * total]
    rest = total - sum(v for _, v, _ in big)
    lines = [f'  {k:28s} {v / MIB:8.1f} MiB  {v / MIB / hours:8.1f} MiB/h'
             + (f'  {v / n:6.0f} B per item of {n}' if n else '') for k, v, n in big]
    lines.append(f'  {"(the rest)":28s} {rest / MIB:8.1f} MiB')
    lines.append(f'  {"sum":28s} {total / MIB:8.1f} MiB  {total / MIB / hours:8.1f} MiB/h  '
                 f'(RSS after align less the import-only child: {held_mib:.1f} MiB)')
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--durations', type=float, nargs='+', default=[300.0, 900.0, 3600.0],
                    help='simulated seconds of the deck scenario, one child each')
    ap.add_argument('--trace', action='store_true',
                    help='also tracemalloc the shortest duration: top allocation sites (slow)')
    ap.add_argument('--child', type=float, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child is not None:
        print(json.dumps(child(a.child, a.trace)))
        return 0
    print(f'{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} at the start; deck scenario, seed 1')
    base = run_child(0.0)
    b = base['child_maxrss_mib']
    print(f'import-only child: peak RSS {b:.1f} MiB (RSS {base["import_rss_mib"]:.1f} MiB after the imports)')
    durations = sorted(a.durations)
    runs = []
    for d in durations:
        r = run_child(d)
        runs.append(r)
        print(f'  {d:g} s done: {r["simulate_s"] + r["align_s"]:.1f} s, peak {r["child_maxrss_mib"]:.1f} MiB',
              flush=True)
    print(f'\n{"duration s":>10s} {"samples":>8s} {"wall s":>7s} {"sim s":>6s} {"peak MiB":>9s} {"- base":>7s} '
          f'{"peak/h":>7s} {"(-base)/h":>9s} {"sim peak":>9s} {"after sim":>9s} {"after align":>11s}')
    for d, r in zip(durations, runs):
        h, pk = d / 3600.0, r['child_maxrss_mib']
        print(f'{d:10g} {r["samples"]:8d} {r["simulate_s"] + r["align_s"]:7.1f} {r["simulate_s"]:6.1f} {pk:9.1f} '
              f'{pk - b:7.1f} {pk / h:7.1f} {(pk - b) / h:9.1f} {r["simulate_peak_mib"]:9.1f} '
              f'{r["simulate_rss_mib"]:9.1f} {r["align_rss_mib"]:11.1f}')
    own = max(abs(r['align_peak_mib'] - r['child_maxrss_mib']) for r in runs)
    print(f'(peak: the child\'s ru_maxrss seen by the parent, os.wait4; the child\'s own reading after align '
          f'differs by at most {own:.1f} MiB; sim peak: the child\'s ru_maxrss after simulate; MiB)')
    hours = np.array(durations) / 3600.0
    peaks = np.array([r['child_maxrss_mib'] for r in runs])
    in_sim = [r['simulate_peak_mib'] >= r['child_maxrss_mib'] - 0.5 for r in runs]
    where = ('inside simulate at every duration' if all(in_sim) else
             'in align at every duration' if not any(in_sim) else
             f'inside simulate at {", ".join(f"{d:g}" for d, i in zip(durations, in_sim) if i)} s, '
             'in align otherwise')
    if len(runs) >= 2:
        k, c = np.polyfit(hours, peaks, 1)
        res = float(np.max(np.abs(peaks - (c + k * hours))))
        kh, ch = np.polyfit(hours, [r['align_rss_mib'] for r in runs], 1)
        print(f'\npeak ~ {c:.0f} MiB + {k:.0f} MiB per simulated hour (least squares over {len(runs)} durations, '
              f'largest residual {res:.1f} MiB; the import-only child: {b:.0f} MiB); the peak is reached {where}; '
              f'RSS after align ~ {ch:.0f} MiB + {kh:.0f} MiB/h (every sample and every estimate of the run kept)')
    last = runs[-1]
    print(f'\nwhat the {durations[-1]:g} s run holds after align ({last["imu"]} IMU, {last["master"]} master, '
          f'{last["ldv"]} LDV samples, {last["estimates"]} estimates):')
    print('\n'.join(summary(last['holdings'], durations[-1] / 3600.0, last['align_rss_mib'] - base['import_rss_mib'])))
    if a.trace:
        d = durations[0]
        print(f'\ntracemalloc, {d:g} s (a separate child):')
        print('\n'.join(run_child(d, trace=True)['trace']))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
