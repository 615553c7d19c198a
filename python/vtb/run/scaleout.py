"""Where a study's runs go: one Rust batch in this process, or tasks on an executor
(docs/scaleout.md).

Every study (sweeps, optimisations, robust studies, design evaluations, the validation and
the robust study) hands its runs to :func:`run_cases`, which reports each run's result as soon
as it is known, so that the study journals it at once:

* in process (``executor=None``): one :func:`vtb.simulate_batch` call on ``threads`` cores;
  its lockstep groups report as each finishes;
* on an executor (a :class:`concurrent.futures.Executor`: a process pool, or Dask's
  ``client.get_executor()``): tasks of ``chunk`` runs of one model (default one lockstep
  group; runs that differ only in their dampers' parameters share a model), each a
  batch on one worker thread, reported as each task completes. Dask reruns the tasks of a
  worker that dies on the others, so a lost worker loses nothing; a process pool that breaks
  reports its unfinished runs as failed (:class:`WorkerLost`), which a study records and
  retries on resume. Only the calling process writes journals, so they stay consistent.

A run's result does not depend on where or with which others it ran (lockstep groups give
each job its own bits), so every path gives the serial result bit for bit. Workers find a
synthesis reduction in the disk cache (:func:`vtb.run.synthesis.cache_dir`; on a cluster, point
``VTB_CACHE_DIR`` at shared storage) and keep it in memory for their later tasks.

:func:`local_cluster` starts a Dask cluster on this machine set up for studies
(:data:`DASK_SETTINGS`); :func:`dask_environment` gives the same settings to workers started
by hand or by a batch system.
"""

from __future__ import annotations

import contextlib
import os
from concurrent.futures import Executor, as_completed
from typing import Callable, Iterator, Optional, Sequence

import numpy as np

from ..config import gateway
from ..config.fields import Config
from ..errors import SolverError, config_error
from .simulate import DEFAULT_LANES, SYNTHESIS_LANES, _reduction, simulate_batch


class WorkerLost(SolverError):
    """The executor lost the worker that held a run (its process died, its pool broke)."""


#: Dask settings for workers that run studies: tasks of seconds of computation, one thread
#: each. Dask's defaults sample every worker thread's stack 100 times a second (its
#: statistical profiler), time every event loop 50 times a second and poll each process's
#: load twice a second; with every core running a worker these take about 5 % of a core per
#: process from the runs (measured idle, 2026-12-03: 0.87 → 0.40 s of processor time per
#: 10 s for a scheduler and two workers), nothing a study needs.
DASK_SETTINGS = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
}


def dask_environment() -> dict:
    """:data:`DASK_SETTINGS` as the environment variables a ``dask worker`` or ``dask
    scheduler`` process reads its configuration from (``DASK_`` and the key with ``__`` for
    ``.``, upper case)."""
    return {"DASK_" + k.replace(".", "__").replace("-", "_").upper(): str(v) for k, v in DASK_SETTINGS.items()}


@contextlib.contextmanager
def local_cluster(n_workers: Optional[int] = None, *, preload: Optional[Config] = None) -> Iterator[Executor]:
    """A Dask cluster on this machine for a study: ``n_workers`` worker processes (default one
    per core this process may use) of one thread each, with :data:`DASK_SETTINGS`; yields its
    executor (tasks not hashed by content, which a study's runs never repeat) and closes the
    cluster after. ``preload``: a configuration whose synthesis reduction every worker loads
    before the cluster is handed over (else each loads it with its first task); this process
    builds it first if the disk cache lacks it, so that the workers only read it."""
    from dask import config as dask_config
    from dask.distributed import Client, LocalCluster

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    n = cores if n_workers is None else n_workers
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise config_error("n_workers", n_workers, "must be a whole number of worker processes ≥ 1")
    if preload is not None:
        _hold_reduction(preload)  # built here, once, not by every worker at the same time
    with dask_config.set(DASK_SETTINGS), LocalCluster(n_workers=int(n), threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        if preload is not None:
            client.run(_hold_reduction, preload)  # reaches every worker, unlike tasks
        yield client.get_executor(pure=False)


def _hold_reduction(config: Config) -> None:
    _reduction(config)


def _task(configs: list) -> list:
    """One executor task: a batch on one worker thread (module level: picklable)."""
    return simulate_batch(configs, threads=1, on_error="return")


def default_chunk(configs: Sequence[Config]) -> int:
    """One lockstep group of the configurations' engine."""
    synthesis = any(c.discretisation.synthesis_cutoff is not None for c in configs)
    return SYNTHESIS_LANES if synthesis else DEFAULT_LANES


def run_cases(configs: Sequence[Config], on_result: Callable, *, executor: Optional[Executor] = None, threads: Optional[int] = None,
              chunk: Optional[int] = None) -> None:
    """Runs ``configs`` and calls ``on_result(i, item)`` for each as soon as it is known (i
    indexes ``configs``; item: the run's metrics dict, or the exception it failed with). See
    the module documentation for the two paths; ``chunk`` (executor only): runs per task."""
    configs = list(configs)
    if not configs:
        return
    if executor is None:
        simulate_batch(configs, threads=threads, on_error="return", on_result=on_result)
        return
    size = chunk or default_chunk(configs)
    # A task holds runs of one model (the core's key), so that its lockstep groups are full.
    members: dict = {}
    for i, c in enumerate(configs):
        members.setdefault(gateway.model_key(c.to_core_json()), []).append(i)
    tasks = [m[a:a + size] for m in members.values() for a in range(0, len(m), size)]
    futures = {executor.submit(_task, [configs[i] for i in t]): t for t in tasks}
    try:
        for fut in as_completed(futures):
            try:
                items = fut.result()
            except Exception as e:  # the executor lost the task's worker
                lost = WorkerLost(" ".join(f"worker failed: {type(e).__name__}: {e}".split()))
                items = [lost] * len(futures[fut])
            for i, item in zip(futures[fut], items):
                on_result(i, item)
    finally:
        for fut in futures:
            fut.cancel()


def run_all(configs: Sequence[Config], *, executor: Optional[Executor] = None, threads: Optional[int] = None, chunk: Optional[int] = None,
            on_result: Optional[Callable] = None, progress=False, desc: str = "vtb runs") -> list:
    """:func:`run_cases`, the items returned in order; given ``on_result`` also reported as
    they come, and counted on a tqdm bar (``progress=True``) or by ``progress(done, total)``."""
    out: list = [None] * len(configs)
    bar = None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(configs), desc=desc, unit="run")
    done = 0

    def keep(i, item):
        nonlocal done
        out[i] = item
        done += 1
        if bar is not None:
            bar.update(1)
        elif callable(progress):
            progress(done, len(configs))
        if on_result is not None:
            on_result(i, item)

    try:
        run_cases(configs, keep, executor=executor, threads=threads, chunk=chunk)
    finally:
        if bar is not None:
            bar.close()
    return out
