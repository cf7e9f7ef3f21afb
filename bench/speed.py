"""The speed goals' numbers in one run: the engine's time per IMU step (15-state vm15, a 100 Hz master
match at every step) against filterpy's KalmanFilter predict + update at n = 15, m = 3 and against
pyins; Monte Carlo runs per minute of the 300 s `deck_paper` (the papers' parked deck) and `deck`
(the carrier as it is: spectral sea, the aircraft on its gear, the master's own rate and
latency) scenarios at 1 and 2 workers (--mc-scenarios); and, with
--against REV, the same engine and Monte Carlo numbers of the code at git revision REV (its
src/ extracted to a temporary directory), measured alternately with today's in the same run so
both see the same machine load.

    scripts/bench.sh speed [--runs 4] [--runs-2 N] [--seconds 60] [--repeat 3] [--against REV] [--graph-runs 1]
    scripts/bench.sh speed --publish [--graph-runs 3]     the goals' table, published
    scripts/bench.sh speed --render                       re-render the last published run

--publish also measures the batch pipeline's peak memory on a 300 s and a 1 h `deck` run
(bench/batch_memory.py's children), saves the run to bench/results/speed.json and renders its
table (bench/speed_table.py) into the README's and docs/speed.md's speed blocks, stamped with the
commit, the date and the machine's load.

Every measurement runs in a child process (`--child PART`, PYTHONPATH pointing at the tree
measured). Engine: TransferAlignment on a simulated `deck_paper` run (--seconds at 100 Hz); per IMU
step the three samples are pushed and process() runs; median over the steps after the first
tenth, best of --repeat. Filter: our KalmanFilter (Joseph form) and filterpy's on the same
n = 15, m = 3 workload with the engine's measurement matrix H = [0 I 0 0 -[u x]], median per
predict + update, best of --repeat, the two filters' blocks of 100 steps in turn. pyins:
bench/monte_carlo.py's peer workload.
Monte Carlo: each scenario (of each tree) first runs 10 s untimed (`--child warm`), so that no timed
run compiles kernels (their disk cache is keyed by the package's sources); --runs runs on one
worker, --runs-2 (default: --runs) on two: the goal's own count is 100 runs on the two cores.
Graph: --graph-runs runs of the default scenario through scripts/run_graph.sh at
--real-time-factor 0 (bench/graph_rtf.py's run; today's tree only: REV's would need its own
built workspace), each with its whole-run RTF, start-up (command to first message recorded),
messages lost and every process's CPU seconds per simulated minute (the nodes' and the
recorder's stats); with them, the DDS transport's own CPU per message (bench/dds_cost.py: a
publisher and its raw subscribers, each a process) and what it comes to in each graph run.
Ratios are only meaningful within a run (a shared machine's load moves every absolute number);
the Monte Carlo's CPU seconds per run (this process and its pool's workers) move less with the
load than its wall time.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import speed_table

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ('alignment_core', 'alignment_experiments')
SETTINGS = ('runs', 'runs_2', 'seconds', 'repeat', 'kf_steps', 'graph_runs', 'mc_scenarios')
"""The arguments that shape the measurements, recorded with a published run."""


# ----- the measurements (child side) -----

def engine_us(seconds: float, repeat: int) -> dict:
    """Median / p95 us per IMU step with its LDV + master match, vm15 on the deck_paper scenario."""
    from alignment_core import pipeline
    from alignment_core.config import scenario
    sc = scenario.load('deck_paper', {'duration_s': seconds})
    inp = pipeline.simulate(sc)
    from filter_bank import engine_step_times
    best, f = engine_step_times(sc, inp, repeat)
    assert best is not None
    return {'median_us': float(np.median(best)), 'p95_us': float(np.quantile(best, 0.95)),
            'updates': f.counters.updates, 'steps': len(inp.imu)}


def kf_workload(steps: int, n: int = 15, m: int = 3, seed: int = 0):
    """Phi (dense, stable), Qd, the engine's vm15 H = [0 I 0 0 -[u x]], R, P0 and measurements."""
    import scipy.linalg as sla
    rng = np.random.default_rng(seed)
    k = rng.standard_normal((n, n))
    phi = sla.expm(0.01 * (k - k.T) - 1e-4 * np.eye(n))
    qd = np.diag(rng.uniform(0.5, 2.0, n)) * 1e-6
    h = np.zeros((m, n))
    h[:, 3:6] = np.eye(3)
    ux, uy, uz = 0.3, -0.2, 0.1                     # a lever-arm velocity, m/s: -[u x] on phi_m
    h[:, 12:15] = -np.array([[0.0, -uz, uy], [uz, 0.0, -ux], [-uy, ux, 0.0]])
    r = np.diag(rng.uniform(0.5, 2.0, m)) * 1e-4
    x = rng.standard_normal(n) * 0.1
    zs = np.empty((steps, m))
    for i in range(steps):
        x = phi @ x + np.sqrt(np.diag(qd)) * rng.standard_normal(n)
        zs[i] = h @ x + np.sqrt(np.diag(r)) * rng.standard_normal(m)
    return phi, qd, h, r, np.eye(n) * 1e-2, zs


KF_BLOCK = 100
"""Steps of one filter timed in a row before the other's (`kf_us`)."""


def kf_us(steps: int, repeat: int) -> dict:
    """Median us per predict + update: ours (Joseph form) and filterpy's, best of repeat. Each
    filter steps on its own, in a loop, KF_BLOCK steps at a time, the two filters' blocks in turn,
    so that both are timed under the same machine conditions (a shared machine's speed changes
    within a run of 3000 steps of either alone)."""
    from filterpy.kalman import KalmanFilter as FpKF

    from alignment_core.estimation.filters import KalmanFilter
    phi, qd, h, r, p0, zs = kf_workload(steps)
    n, m = h.shape[1], h.shape[0]
    clock = time.perf_counter_ns

    def both() -> tuple[float, float]:
        f = KalmanFilter(np.zeros(n), p0)
        g = FpKF(dim_x=n, dim_z=m)
        g.F, g.Q, g.H, g.R, g.P = phi, qd, h, r, p0.copy()
        ts, tg = np.empty(len(zs)), np.empty(len(zs))
        for a in range(0, len(zs), KF_BLOCK):
            for i in range(a, min(a + KF_BLOCK, len(zs))):
                t0 = clock()
                f.predict(phi, qd)
                f.update(zs[i], h, r)
                ts[i] = clock() - t0
            for i in range(a, min(a + KF_BLOCK, len(zs))):
                t0 = clock()
                g.predict()
                g.update(zs[i])
                tg[i] = clock() - t0
        return float(np.median(ts)) * 1e-3, float(np.median(tg)) * 1e-3
    a, b = zip(*(both() for _ in range(repeat)))
    return {'ours_us': min(a), 'filterpy_us': min(b)}


def pyins_us(seconds: float) -> dict:
    sys.path.insert(0, str(ROOT / 'bench'))
    from monte_carlo import pyins_filter_seconds
    got = pyins_filter_seconds(seconds, 100.0, 0.01)
    if got is None:
        return {}
    t, n = got
    return {'pyins_us': 1e6 * t / n, 'pyins_steps': n}


def mc_rpm(runs: int, workers: int, scenario: str) -> dict:
    """Runs per minute of a 300 s deck scenario (scored as bench/monte_carlo.py does)."""
    from alignment_experiments import monte_carlo
    specs = [monte_carlo.RunSpec(index=i, cell='bench', scenario=scenario, overrides=(), seed=100 + i,
                                 score_at=250.0) for i in range(runs)]
    def cpu() -> float:          # this process and its reaped children (the pool's workers, once shut down)
        own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime
    c, t = cpu(), time.perf_counter()
    monte_carlo.run_many(specs, workers=workers, progress=False)
    wall = time.perf_counter() - t
    return {'runs': runs, 'wall_s': wall, 'runs_per_min': 60.0 * runs / wall, 'cpu_s_per_run': (cpu() - c) / runs}


def warm(scenario: str) -> dict:
    """A short run of the scenario, untimed: its kernels compiled into the disk cache (keyed by the
    package's sources: a commit that changed them compiles afresh) before a timed run loads them."""
    from alignment_core import pipeline
    from alignment_core.config import scenario as scenarios
    t = time.perf_counter()
    pipeline.run(scenarios.load(scenario, {'duration_s': 10.0}), keep_truth=False)
    return {'warm_s': time.perf_counter() - t}


def batch_memory() -> dict:
    """Peak RSS of the batch pipeline on a 300 s and a 1 h `deck` run (bench/batch_memory.py's children)
    and the line through them."""
    import batch_memory as bm
    peaks = {d: bm.run_child(d)['child_maxrss_mib'] for d in (300.0, 3600.0)}
    per_hour = (peaks[3600.0] - peaks[300.0]) / (3300.0 / 3600.0)
    return {'peak_300s_mib': peaks[300.0], 'peak_1h_mib': peaks[3600.0], 'per_hour_mib': per_hour,
            'base_mib': peaks[3600.0] - per_hour, 'import_only_mib': bm.run_child(0.0)['child_maxrss_mib']}


def child(part: str, a: argparse.Namespace) -> None:
    if part == 'engine':
        out = engine_us(a.seconds, a.repeat)
    elif part == 'kf':
        out = kf_us(a.kf_steps, a.repeat)
    elif part == 'pyins':
        out = pyins_us(a.peer_seconds)
    elif part == 'warm':
        out = warm(a.scenario)
    elif part.startswith('mc'):
        out = mc_rpm(a.runs, int(part[2:]), a.scenario)
    else:
        raise SystemExit(f'unknown part {part}')
    print(json.dumps(out))


# ----- the driver -----

def extract(rev: str, into: Path) -> str:
    """src/<package> of git revision rev under `into`; the PYTHONPATH entries to import it."""
    tar = subprocess.run(['git', '-C', str(ROOT), 'archive', rev, *(f'src/{p}' for p in PACKAGES)],
                         check=True, capture_output=True).stdout
    subprocess.run(['tar', '-x', '-C', str(into)], input=tar, check=True)
    return os.pathsep.join(str(into / 'src' / p) for p in PACKAGES)


def run(part: str, a: argparse.Namespace, pythonpath: str | None, scenario: str = 'deck_paper') -> dict:
    env = dict(os.environ)
    if pythonpath:
        env['PYTHONPATH'] = pythonpath + os.pathsep + env.get('PYTHONPATH', '')
    runs = a.runs_2 if part == 'mc2' and a.runs_2 else a.runs
    args = [sys.executable, __file__, '--child', part, '--runs', str(runs), '--seconds', str(a.seconds),
            '--repeat', str(a.repeat), '--kf-steps', str(a.kf_steps), '--peer-seconds', str(a.peer_seconds),
            '--scenario', scenario]
    p = subprocess.run(args, env=env, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        raise RuntimeError(f'{part}: {p.stderr[-2000:]}')
    return json.loads(p.stdout.strip().splitlines()[-1])


def streaming_cpu_s(g: dict) -> float:
    """The CPU seconds a graph run's processes took after their start-up (each process's total less
    its CPU time when it began to spin, the recorder's at its first message)."""
    ready = g.get('cpu_ready_s', {})
    return sum(c - (ready.get(n) or 0.0) for n, c in g['cpu_s'].items() if c is not None)


def transport(graphs: list[dict]) -> dict:
    """The DDS transport's CPU per message (bench/dds_cost.py) and, for each graph run, what it
    comes to over the run's messages and readers, beside the CPU its processes took."""
    import dds_cost  # bench/dds_cost.py
    cost = dds_cost.measure()
    cpus = os.cpu_count() or 1
    runs = [{**dds_cost.transport_bound(cost, g['topics'], g['sim_time_s'], cpus),
             'graph_cpu_s': streaming_cpu_s(g)} for g in graphs]
    return {**cost, 'runs': runs}


def interpreter() -> str:
    """The Python version and the interpreter the venv was made from: builds of one version differ
    in speed (a distribution's, optimised with profiles and at link time, against pyenv's default)."""
    return f'Python {platform.python_version()}, {getattr(sys, "_base_executable", sys.executable)}'


def cpu_model() -> str:
    """The processor's model name and clock from /proc/cpuinfo (platform.processor() without it,
    '' when neither says): machines of one kind differ in speed, so a table's stamp says which one
    it was measured on."""
    try:
        info = Path('/proc/cpuinfo').read_text()
    except OSError:
        return platform.processor()
    name = re.search(r'^model name\s*:\s*(.+)$', info, re.M)
    mhz = re.search(r'^cpu MHz\s*:\s*([0-9.]+)$', info, re.M)
    return ' '.join(filter(None, [name.group(1).strip() if name else '',
                                  f'{float(mhz.group(1)) / 1000:.1f} GHz' if mhz else '']))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--runs', type=int, default=4, help='Monte Carlo runs per worker setting')
    ap.add_argument('--runs-2', type=int, default=None, help='Monte Carlo runs on two workers (default: --runs)')
    ap.add_argument('--seconds', type=float, default=60.0, help='simulated seconds of the engine run')
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--kf-steps', type=int, default=3000)
    ap.add_argument('--peer-seconds', type=float, default=20.0, help='simulated seconds of the pyins run')
    ap.add_argument('--graph-runs', type=int, default=1, help='runs of the default scenario through the graph')
    ap.add_argument('--mc-scenarios', nargs='+', default=['deck_paper', 'deck'],
                    help="the Monte Carlo's scenarios (300 s each): the papers' deck and the carrier as it is")
    ap.add_argument('--scenario', default='deck_paper', help=argparse.SUPPRESS)
    ap.add_argument('--against', metavar='REV', help='also measure git revision REV (e.g. main) in the same run')
    ap.add_argument('--publish', action='store_true',
                    help='also measure the batch memory of a 300 s and a 1 h deck run, save the run to '
                         'bench/results/speed.json and render its table into the README and docs/speed.md')
    ap.add_argument('--render', action='store_true', help='only render bench/results/speed.json (no measurement)')
    ap.add_argument('--child', help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.child, a)
        return
    if a.render:
        speed_table.main()
        return
    version, load0 = speed_table.code_version(), os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d:
        trees: dict[str, str | None] = {'today': None}
        if a.against:
            trees = {a.against: extract(a.against, Path(d)), 'today': None}
        print(f'{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} at the start; trees: {", ".join(trees)}')
        eng = {name: run('engine', a, pp) for name, pp in trees.items()}
        kf = run('kf', a, None)
        peer = run('pyins', a, None)
        for sc in a.mc_scenarios:
            for pp in trees.values():
                run('warm', a, pp, sc)
        mc = {(sc, name, w): run(f'mc{w}', a, pp, sc) for sc in a.mc_scenarios for w in (1, 2)
              for name, pp in trees.items()}
        from graph_rtf import graph as graph_run  # bench/graph_rtf.py: run_graph.sh at a real-time factor
        graphs = [graph_run(0.0) for _ in range(a.graph_runs)]
        dds = transport(graphs) if graphs else None
        memory = batch_memory() if a.publish else None
    print(f'\nengine per IMU step + 100 Hz master match (vm15, deck_paper, {a.seconds:g} s, best of {a.repeat}):')
    for name, e in eng.items():
        print(f'  {name:12s} median {e["median_us"]:7.1f} us  p95 {e["p95_us"]:7.1f} us  ({e["updates"]} updates)')
    print(f'bare filter predict + update, n=15 m=3 (engine H), best of {a.repeat}: ours {kf["ours_us"]:.1f} us, '
          f'filterpy {kf["filterpy_us"]:.1f} us -> {kf["filterpy_us"] / kf["ours_us"]:.2f}x filterpy\'s speed')
    today = eng['today']['median_us']
    print(f'whole engine step (today) vs filterpy\'s bare predict + update: {today / kf["filterpy_us"]:.2f}x its time')
    if peer:
        print(f'pyins run_feedback_filter: {peer["pyins_us"]:.0f} us per step ({peer["pyins_steps"]} velocity updates) '
              f'-> the engine step is {peer["pyins_us"] / today:.0f}x faster')
    else:
        print('pyins: not installed (scripts/bench.sh installs requirements-bench.txt)')
    print(f'Monte Carlo, 300 s, {a.runs} runs on one worker, {a.runs_2 or a.runs} on two:')
    for (sc, name, w), r in mc.items():
        print(f'  {sc:10s} {name:12s} workers={w}: {r["wall_s"]:7.1f} s  {r["runs_per_min"]:6.1f} runs/min  '
              f'-> 100 runs in {100 / r["runs_per_min"]:5.1f} min; {r["cpu_s_per_run"]:5.1f} CPU s per run')
    for g in graphs:
        start = 'unknown' if g['startup_s'] is None else f'{g["startup_s"]:.2f} s'
        print(f'graph, default scenario, --real-time-factor 0: whole-run RTF {g["whole_run_rtf"]:.2f}, first message '
              f'{start} after the command, {g["lost"]} lost, the scored estimate '
              f'{"equal to" if g["same_estimate"] else "DIFFERENT FROM"} the batch pipeline\'s; '
              'CPU s per simulated minute: '
              + ', '.join(f'{n} {60.0 * c / g["sim_time_s"]:.1f}' for n, c in g['cpu_s'].items() if c is not None))
    if dds:
        print(f'DDS transport, CPU per Odometry message: publisher {dds["a_us"]:.1f} + {dds["b_us"]:.1f} us per '
              f'reader, a raw subscriber {dds["c_us"]:.1f} us; in the graph runs ~'
              + ', '.join(f'{b["transport_cpu_s"]:.1f}' for b in dds['runs']) + ' CPU s, the processes\' '
              + ', '.join(f'{b["graph_cpu_s"]:.1f}' for b in dds['runs']))
    if memory:
        print(f'batch peak RSS, deck: {memory["peak_1h_mib"]:.0f} MiB for 1 h; ~ {memory["base_mib"]:.0f} MiB + '
              f'{memory["per_hour_mib"]:.0f} MiB per simulated hour')
    if a.publish:
        args = shlex.join(sys.argv[1:])
        out = {'stamp': {'commit': version, 'date': time.strftime('%Y-%m-%d', time.gmtime()),
                         'cpus': os.cpu_count(), 'cpu': cpu_model(), 'python': interpreter(), 'load_start': load0,
                         'load_end': os.getloadavg()[0],
                         'command': f'scripts/bench.sh speed {args}',
                         'settings': {k: v for k, v in vars(a).items() if k in SETTINGS and v is not None}},
               'engine': eng['today'], 'kf': kf, 'pyins': peer or None, 'graphs': graphs, 'dds': dds,
               'memory': memory,
               'mc': {sc: {str(w): mc[(sc, 'today', w)] for w in (1, 2)} for sc in a.mc_scenarios}}
        speed_table.RESULT.parent.mkdir(exist_ok=True)
        speed_table.RESULT.write_text(json.dumps(out, indent=1) + '\n')
        speed_table.main()
    if a.against:
        e0 = eng[a.against]['median_us']
        print(f'today vs {a.against}: engine step {e0 / today:.2f}x faster')
        for sc in a.mc_scenarios:
            rpm = [mc[(sc, 'today', w)]['runs_per_min'] / mc[(sc, a.against, w)]['runs_per_min'] for w in (1, 2)]
            cpu = [mc[(sc, a.against, w)]['cpu_s_per_run'] / mc[(sc, 'today', w)]['cpu_s_per_run'] for w in (1, 2)]
            print(f'  Monte Carlo {sc}: 1 worker {rpm[0]:.2f}x, 2 workers {rpm[1]:.2f}x (wall); '
                  f'CPU per run 1 worker {cpu[0]:.2f}x, 2 workers {cpu[1]:.2f}x less')


if __name__ == '__main__':
    main()
