"""Monte Carlo engine: N seeds of a scenario (times the cells of a sweep) through the batch
pipeline, in parallel processes on this machine or on a Dask cluster, reproducibly.

Each run is independent and fully defined by its RunSpec (scenario, dotted overrides,
seed), so the results do not depend on the number of workers, their order or the machine
they ran on; results come back in spec order.

Dask (`dask[distributed]`, installed by setup.sh): start a scheduler and workers from a shell
that sourced scripts/env.sh
(`dask scheduler`, `dask worker tcp://HOST:8786 --nthreads 1`), then pass
`--scheduler tcp://HOST:8786` (or `--scheduler local` for a local Dask cluster).
"""
from __future__ import annotations

import gc
import math
import multiprocessing
import os
import sys
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core import compiled, pipeline
from alignment_core.config import scenario
from alignment_core.estimation.outputs import Estimate
from alignment_core.geometry.rotations import relative_rotvec_batch
from alignment_core.units import ARCMIN

from .statistics import nees, settling_time


@dataclass(frozen=True)
class RunSpec:
    """One run: `cell` names the sweep point, `values` are its table columns."""
    index: int
    cell: str
    scenario: str
    overrides: tuple[tuple[str, object], ...]
    seed: int
    score_at: str | float = 'release'            # 'release', 'release+S' or seconds after the start
    settle_arcmin: tuple[float, float, float] = (1.0, 1.0, 1.0)
    values: tuple[tuple[str, object], ...] = ()
    quantity: str = 'misalignment'               # or 'attitude': the slave INS attitude error (nav frame)


@dataclass
class RunOutcome:
    """Scored result of one run. Errors and sigmas in arcmin, times in seconds from start."""
    spec: RunSpec
    score_time_s: float
    err: np.ndarray            # (3,) estimate - truth at the score time
    sigma: np.ndarray          # (3,) filter 1-sigma at the score time
    settle_s: np.ndarray       # (3,) settling time per axis (NaN: never)
    nis_mean: float
    updates: int
    t_s: np.ndarray = field(repr=False)      # (K,) output times
    err_t: np.ndarray = field(repr=False)    # (K, 3) error history, arcmin
    sigma_t: np.ndarray = field(repr=False)  # (K, 3) 1-sigma history, arcmin
    wall_s: float = 0.0

    @property
    def nees(self) -> float:
        return float(nees(self.err, self.sigma))


def true_misalignment(inp: pipeline.Inputs) -> np.ndarray:
    """(K, 3) rad: the aircraft IMU axes relative to the master's (ship body) axes at every ship
    sample, from the truth attitudes (mounting, static and dynamic flexure); held at its
    release value once the aircraft has left the deck (the filter's estimate is held too)."""
    rel = relative_rotvec_batch(inp.ships.q_nb, inp.truth['q_nb'])
    on = np.asarray(inp.truth['on_deck'], dtype=bool)
    if np.any(on) and not np.all(on):
        last = int(np.flatnonzero(on)[-1])
        rel[last + 1:] = rel[last]
    return rel


def truth_indices(truth_t_ns: np.ndarray, t_ns: np.ndarray) -> np.ndarray:
    """(K,) index of the first truth sample at or after each time t_ns (the last one beyond)."""
    return np.minimum(np.searchsorted(truth_t_ns, t_ns), len(truth_t_ns) - 1)


def misalignment_errors(est: Sequence[Estimate], truth_t_ns: np.ndarray,
                        rel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3) misalignment error (rad) of each estimate against the truth `rel` (K_truth, 3), taken
    at the estimate's time of validity (its stamp less the master latency the filter is told:
    the relative attitude it estimated, docs/carrier.md), and its (K, 3) 1-sigma."""
    k_truth = truth_indices(truth_t_ns, np.array([e.validity_ns for e in est], dtype=np.int64))
    err = np.array([e.misalignment for e in est]).reshape(-1, 3) - rel[k_truth]
    return err, np.array([e.misalignment_sigma for e in est]).reshape(-1, 3)


def attitude_errors(est: Sequence[Estimate], q_true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3) slave attitude error phi (nav frame, C_est = (I - [phi x]) C_true) and its 1-sigma
    from the filter's attitude covariance, at each estimate."""
    q_est = np.array([e.q_nb for e in est]).reshape(-1, 4)
    norm = np.linalg.norm(q_est, axis=1)
    ok = np.isfinite(norm) & (norm > 0.5)          # a diverged filter (NaN or zero quaternion) scores NaN
    phi = np.full((len(q_est), 3), np.nan)
    if np.any(ok):
        phi[ok] = (Rotation.from_quat(q_true[ok]) * Rotation.from_quat(q_est[ok]).inv()).as_rotvec()
    with np.errstate(invalid='ignore'):
        sig = np.sqrt(np.array([np.diag(e.attitude_cov) for e in est]).reshape(-1, 3))
    return phi, sig


def run_one(spec: RunSpec) -> RunOutcome:
    """Simulate and align one run in this process, score it."""
    wall = time.perf_counter()
    sc = scenario.load(spec.scenario, dict(spec.overrides), seed=spec.seed)
    inp = pipeline.simulate(sc)
    est = pipeline.align(sc, inp).outputs
    t0 = sc.t0_ns
    t_ns = np.array([e.t_ns for e in est], dtype=np.int64)
    if spec.quantity == 'attitude':
        k_truth = truth_indices(inp.ships.t_ns, np.array([e.navigation_ns for e in est], dtype=np.int64))
        err, sig = attitude_errors(est, inp.truth['q_nb'][k_truth])
    elif spec.quantity == 'misalignment':
        err, sig = misalignment_errors(est, inp.ships.t_ns, true_misalignment(inp))
    else:
        raise ValueError(f"quantity must be 'misalignment' or 'attitude', got {spec.quantity!r}")
    on_deck = inp.ships.t_ns[inp.truth['on_deck']]
    t_release = int(on_deck[-1]) if len(on_deck) else int(t_ns[-1])
    if isinstance(spec.score_at, str) and spec.score_at.startswith('release'):
        t_score = t_release + int(round(float(spec.score_at[len('release'):] or 0.0) * 1e9))
    else:
        t_score = t0 + int(round(float(spec.score_at) * 1e9))
    k = int(np.searchsorted(t_ns, t_score, side='right')) - 1
    if k < 0:
        raise RuntimeError(f'{spec.cell} seed {spec.seed}: no filter output before the score time')
    t_s = (t_ns - t0) / 1e9
    err_a, sig_a = err / ARCMIN, sig / ARCMIN
    settle = np.array([settling_time(t_s[:k + 1], err_a[:k + 1, i], spec.settle_arcmin[i]) for i in range(3)])
    nis = np.array([e.nis for e in est[:k + 1]], dtype=float)
    nis = nis[np.isfinite(nis)]
    return RunOutcome(spec=spec, score_time_s=float(t_s[k]), err=err_a[k], sigma=sig_a[k], settle_s=settle,
                      nis_mean=float(np.mean(nis)) if len(nis) else math.nan,
                      updates=int(est[k].updates), t_s=t_s, err_t=err_a.astype(np.float32),
                      sigma_t=sig_a.astype(np.float32), wall_s=time.perf_counter() - wall)


def _restore_environ(saved: dict[str, str]) -> None:
    """Put back this process's environment: Dask's nanny writes its workers' variables into it
    (MALLOC_TRIM_THRESHOLD_, which also fixes glibc's mmap threshold in every process started
    from here afterwards: graph nodes, a test's probes)."""
    for k in set(os.environ) - set(saved):
        del os.environ[k]
    os.environ.update(saved)


def make_executor(workers: int, scheduler: str | None = None) -> Executor | None:
    """A process pool of `workers` (None: run inline when workers <= 1), or a Dask cluster's
    executor when `scheduler` is an address or 'local'."""
    if scheduler:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise SystemExit('--scheduler needs Dask (requirements.txt): run scripts/setup.sh') from None
        environ = dict(os.environ)
        cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1, processes=True) \
            if scheduler == 'local' else None
        _restore_environ(environ)
        client = Client(cluster if cluster is not None else scheduler)
        ex = client.get_executor()
        shutdown = ex.shutdown

        def close(wait: bool = True, **kw) -> None:
            """Shut the executor down, then its client and (local) cluster: no worker outlives the run."""
            shutdown(wait=wait, **kw)
            client.close()
            if cluster is not None:
                cluster.close()
            _restore_environ(environ)
        ex.shutdown = close
        return ex
    if workers <= 1:
        return None
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context('fork'))


@contextmanager
def forking_pool() -> Iterator[None]:
    """Around the submissions to a pool of forked workers: numba imported once here, not in each
    worker, and the heap frozen (unless someone else froze it), so that no worker's collection
    walks, and so copies, the pages it inherits; thawed after."""
    compiled.activate()
    if gc.get_freeze_count():
        yield
        return
    gc.collect()
    try:
        gc.freeze()
        yield
    finally:
        gc.unfreeze()


def run_many(specs: list[RunSpec], workers: int = 1, scheduler: str | None = None,
             progress: bool | None = None) -> list[RunOutcome]:
    """Run every spec; outcomes in spec order. Progress bar on stderr when it is a terminal."""
    from tqdm import tqdm
    if progress is None:
        progress = sys.stderr.isatty()
    out: list[RunOutcome | None] = [None] * len(specs)
    bar = tqdm(total=len(specs), disable=not progress, unit='run', file=sys.stderr)
    ex = make_executor(workers, scheduler)
    try:
        if ex is None:
            for i, s in enumerate(specs):
                out[i] = run_one(s)
                bar.update()
        else:
            with forking_pool() if isinstance(ex, ProcessPoolExecutor) else nullcontext():
                futs = {ex.submit(run_one, s): i for i, s in enumerate(specs)}
            for f in as_completed(futs):
                out[futs[f]] = f.result()
                bar.update()
    finally:
        bar.close()
        if ex is not None:
            ex.shutdown()
    done = [o for o in out if o is not None]
    assert len(done) == len(specs)          # every spec ran (a failed run raised above)
    return done
