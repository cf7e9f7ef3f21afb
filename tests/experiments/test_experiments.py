"""The Monte Carlo engine and every catalogued experiment, in tiny versions: reproducible
results files, reports that render, and numbers that make physical sense."""
import dataclasses
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from alignment_core.config import scenario
from alignment_experiments import monte_carlo, publish, report, results
from alignment_experiments.catalogue import CATALOGUE
from alignment_experiments.cli import main

PNG_MAGIC = b'\x89PNG\r\n\x1a\n'


def _run(exp, out: Path, workers: int):
    specs = exp.specs()
    outcomes = monte_carlo.run_many(specs, workers=workers, progress=False)
    results.write(out, exp, outcomes, exp.seeds, 1, 1.0, workers)
    report.write_report(out, exp, outcomes, exp.seeds, 1)
    return outcomes


def _expected_velocity_updates(exp, row) -> tuple[int, int]:
    """The range of velocity-matching updates up to a run's score time, from its scenario alone:
    one per match instant (an LDV or master sample, whichever stream is slower) after the first
    master sample (which initialises the filter) while the aircraft is on the deck (until the
    release), none if the LDV head sits out of range of the aircraft's start spot (the aircraft
    only moves away from a head behind it). A beam loses the reflector during the stroke when
    the spot runs out of its line of sight: then every parked instant up to the launch, at most
    every one up to the release. A master latency (L, jitter J) delays the last instants: those
    stamped up to the score time are valid L to L + J before it, and the output's own sample may
    wait for the slave to reach it."""
    cell = next(c for c in exp.cells if c.label == row['cell'])
    sc = scenario.load(exp.scenario, dict(exp.base + cell.overrides), seed=int(row['seed']))
    if 0.0 < sc.ldv.max_range_m < -sc.ldv.head_offset_m:
        return 0, 0
    t_end = float(row['score_time_s'])
    rate = min(sc.ldv.rate_hz or sc.rate_hz, sc.master.rate_hz or sc.rate_hz)
    lat, jit = sc.master.latency_s, sc.master.latency_jitter_s
    cat = sc.aircraft.catapult
    if cat.enabled:
        t_end = min(t_end, cat.launch_time_s + cat.stroke_s)
        if sc.ldv.mode == 'beam':
            return math.floor(rate * (cat.launch_time_s - lat - jit)) - 1, round(rate * t_end)
    if lat or jit:
        return math.floor(rate * (t_end - lat - jit)) - 1, math.floor(rate * (t_end - lat))
    return round(rate * t_end), round(rate * t_end)


def test_same_experiment_same_results_whatever_the_workers(tmp_path):
    exp = CATALOGUE.get('seed000_table1').quick(seeds=2)
    exp = dataclasses.replace(exp, cells=exp.cells[:2])
    a = _run(exp, tmp_path / 'a', workers=1)
    b = _run(exp, tmp_path / 'b', workers=2)
    for f in ('runs.csv', 'summary.csv', 'meta.json'):
        assert (tmp_path / 'a' / f).read_bytes() == (tmp_path / 'b' / f).read_bytes(), f
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.err_t, y.err_t)
    # different seeds give different numbers (the seed reaches the simulation)
    assert a[0].err.tolist() != a[1].err.tolist()


def _dask_clients_left() -> int:
    """Dask clients still open in this process (run_many must close its client and cluster)."""
    from distributed import default_client
    try:
        client = default_client()
    except ValueError:              # none left open
        return 0
    cluster = client.cluster
    client.close()
    if cluster is not None:
        cluster.close()
    return 1


def test_dask_local_cluster_gives_the_process_pool_results(tmp_path, monkeypatch):
    """`--scheduler local` runs the specs on a local Dask cluster (dask[distributed], pinned in
    requirements.txt) and writes the same results files, byte for byte, as the process pool."""
    made = []
    make_executor = monte_carlo.make_executor

    def spy(workers, scheduler=None):
        ex = make_executor(workers, scheduler)
        made.append(type(ex).__module__.split('.')[0])
        return ex
    monkeypatch.setattr(monte_carlo, 'make_executor', spy)
    args = ['consistency_catapult', '--quick', '--seeds', '3', '--workers', '2']
    environ = dict(os.environ)
    assert main(args + ['--out', str(tmp_path / 'pool')]) == 0
    try:
        assert main(args + ['--scheduler', 'local', '--out', str(tmp_path / 'dask')]) == 0
    finally:
        left = _dask_clients_left()
    assert left == 0, 'run_many left its Dask client open'
    assert 'MALLOC_TRIM_THRESHOLD_' not in os.environ or 'MALLOC_TRIM_THRESHOLD_' in environ, \
        "Dask's nanny variables leaked into this process's environment"
    assert made == ['concurrent', 'distributed']
    for f in ('runs.csv', 'summary.csv', 'meta.json'):
        assert (tmp_path / 'pool' / f).read_bytes() == (tmp_path / 'dask' / f).read_bytes(), f
    a, b = np.load(tmp_path / 'pool' / 'series.npz'), np.load(tmp_path / 'dask' / 'series.npz')
    assert sorted(a.files) == sorted(b.files) and len(a.files) == 3 * 3
    for k in a.files:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


@pytest.mark.parametrize('name', sorted(CATALOGUE.experiments))
def test_quick_experiment_report(tmp_path, name):
    out = tmp_path / name
    assert main([name, '--quick', '--workers', '2', '--out', str(out)]) == 0
    exp = CATALOGUE.get(name).quick()
    rows = results.read_runs(out / 'runs.csv')
    assert len(rows) == len(exp.cells) * 2
    for r in rows:
        err = [float(r[f'err_{a}_arcmin']) for a in exp.axes]
        sig = [float(r[f'sigma_{a}_arcmin']) for a in exp.axes]
        assert all(np.isfinite(err)) and all(s > 0 for s in sig)
        lo, hi = _expected_velocity_updates(exp, r)
        assert lo <= int(r['updates']) <= hi, r['cell']
        nis = float(r['nis_mean'])                  # from LDV or Doppler updates: some in every run
        assert np.isfinite(nis) and nis > 0, r['cell']
    md = (out / 'report.md').read_text()
    assert md.startswith('# ') and '## Results per cell' in md and '## Plots' in md
    assert md.count('\n| ') >= len(exp.cells) + 1          # header + one row per cell at least
    for line in md.splitlines():
        if line.startswith('!['):
            png = out / line[line.index('(') + 1:-1]
            assert png.read_bytes()[:8] == PNG_MAGIC and png.stat().st_size > 5000
    summary = results.read_runs(out / 'summary.csv')
    assert len(summary) == 3 * len(exp.cells)
    publish.check_fresh(name, out / 'runs.csv')       # docs/results.md publishes what this code gives


def test_seed000_physics_in_the_report(tmp_path):
    """With integrated increments the catapult stroke leaves the KF far below the initial
    misalignment (tens of arcmin), and point samples of the 100 Hz vibration are worse than
    increments (aliasing: seed 000's note)."""
    exp = CATALOGUE.get('seed000_table1').quick(seeds=2)
    outcomes = monte_carlo.run_many(exp.specs(), workers=2, progress=False)
    by = results.cells_of(outcomes)
    inc = [o for c, runs in by.items() for o in runs if 'increment' in c and 'filter=kf' in c and 'mps2=5 ' in c]
    smp = [o for c, runs in by.items() for o in runs if 'sample' in c and 'filter=kf' in c and 'mps2=5 ' in c]
    assert inc and smp
    rms_inc = np.sqrt(np.mean([o.err ** 2 for o in inc], axis=0))
    rms_smp = np.sqrt(np.mean([o.err ** 2 for o in smp], axis=0))
    assert np.all(rms_inc < 1.0)                   # arcmin; initial misalignment is 10-30'
    assert rms_smp[1] > 5 * rms_inc[1]             # pitch: the aliased accelerometer error
    assert all(o.score_time_s == pytest.approx(8.0) for o in outcomes)   # release: 5 s + 3 s stroke


def test_unknown_experiment_is_a_clear_error(capsys):
    with pytest.raises(SystemExit):
        main(['no_such_experiment'])
    assert 'unknown experiment' in capsys.readouterr().err


def test_a_forked_pool_inherits_a_frozen_heap_and_numba_and_the_heap_is_thawed_after():
    """forking_pool: workers forked inside it find numba imported and the heap they inherit frozen
    (their collections skip it); the parent's heap is thawed after, and a heap someone else froze
    is left frozen."""
    import gc
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    fresh = subprocess.run([sys.executable, '-c', (
        'import sys\n'
        'from alignment_experiments import monte_carlo\n'
        'before = "numba" in sys.modules\n'
        'with monte_carlo.forking_pool():\n'
        '    print(before, "numba" in sys.modules)\n')], capture_output=True, text=True, check=True)
    assert fresh.stdout.split() == ['False', 'True']        # numba imported by the context, not before
    before = gc.get_freeze_count()              # 0 unless an earlier test left a freeze
    with monte_carlo.forking_pool():
        assert gc.get_freeze_count() > 0
        with ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context('fork')) as ex:
            inherited = ex.submit(gc.get_freeze_count).result()
    # thawed (a count, not equality: a frozen object another thread frees leaves the permanent generation)
    assert inherited > 0 and (gc.get_freeze_count() > 0) == (before > 0)
    with pytest.raises(RuntimeError), monte_carlo.forking_pool():
        raise RuntimeError('a run failed')
    assert (gc.get_freeze_count() > 0) == (before > 0)
    gc.freeze()
    try:
        with monte_carlo.forking_pool():
            pass
        assert gc.get_freeze_count() > 0                # still frozen: not thawed by the pool
    finally:
        gc.unfreeze()
