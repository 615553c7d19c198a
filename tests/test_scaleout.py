"""Studies on executors (vtb.scaleout, docs/scaleout.md): every study runs on a Dask cluster
and gives its serial result bit for bit; a worker killed mid-study loses nothing (Dask reruns
its tasks, the journals hold every case once); a broken process pool reports its runs as
failed (WorkerLost), which a study retries on resume."""

import math
import os
import signal

import numpy as np
import pytest

import vtb
from vtb.run import scaleout
from vtb.article.tid_problem import COLUMNS, read_journal

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl:
        with distributed.Client(cl) as client:
            yield client


ROBUST = dict(b_t=[5.0], k_t=[1e8, 2e8], c_t=[1e3], samples=2, speeds=[70.0, 80.0])


def _same_sweeps(a, b):
    assert [(v, s) for v, s, _ in a.sweeps] == [(v, s) for v, s, _ in b.sweeps]
    for (_, _, x), (_, _, y) in zip(a.sweeps, b.sweeps):
        for k in COLUMNS:
            if k == "error":
                assert list(x.columns[k]) == list(y.columns[k])
            else:
                np.testing.assert_array_equal(x.columns[k], y.columns[k])


def test_a_killed_worker_loses_nothing(short, cluster, tmp_path):
    serial = vtb.sweep(short, **ROBUST, progress=False)
    pids = cluster.run(os.getpid)  # worker address -> process id
    killed = []

    def kill_one(done, total):
        if not killed:  # SIGKILL one worker process after the first finished run
            worker = sorted(pids)[0]
            os.kill(pids[worker], signal.SIGKILL)
            killed.append(worker)

    out = tmp_path / "robust"
    res = vtb.sweep(short, **ROBUST, out=out, executor=cluster.get_executor(), chunk=1, progress=kill_one)
    assert killed
    _same_sweeps(serial, res)
    for journal in sorted(out.glob("*.csv")):
        rows = read_journal(journal)
        keys = [(b, k, c) for b, k, c in zip(rows.columns["b_t"], rows.columns["k_t"], rows.columns["c_t"])]
        assert len(keys) == len({tuple("nan" if math.isnan(v) else v for v in key) for key in keys}) == 3, journal


def test_every_study_gives_its_serial_result_on_a_cluster(short, cluster, tmp_path):
    ex = cluster.get_executor()
    # a single-case sweep and optimisation
    grid = dict(b_t=[2.0, 5.0], k_t=[1e8], c_t=[1e3])
    s0, s1 = vtb.sweep(short, **grid, progress=False), vtb.sweep(short, **grid, executor=ex, progress=False)
    for k in COLUMNS:
        assert list(s0.columns[k]) == list(s1.columns[k]) if k == "error" else np.array_equal(s0.columns[k], s1.columns[k], equal_nan=True)
    o0 = vtb.optimize(short, pop_size=4, n_gen=2, seed=1, progress=False)
    o1 = vtb.optimize(short, pop_size=4, n_gen=2, seed=1, progress=False, executor=ex, checkpoint=tmp_path / "o.npz")
    assert o0.moga.history == o1.moga.history
    for k in o0.pareto:
        assert np.array_equal(o0.pareto[k], o1.pareto[k], equal_nan=True), k
    # over samples and speeds: the robust optimisation and a design evaluation
    kw = dict(samples=2, speeds=[70.0, 80.0], pop_size=4, n_gen=2, seed=1, progress=False)
    r0, r1 = vtb.optimize(short, **kw), vtb.optimize(short, **kw, executor=ex)
    assert r0.evaluated == r1.evaluated and r0.best() == r1.best()
    design = dict(b_t=5.0, k_t=2e8, c_t=1e3)
    e0 = vtb.evaluate_design(short, design, samples=2, speeds=[70.0, 80.0])
    e1 = vtb.article.robust.evaluate_designs(short, [design], samples=2, speeds=[70.0, 80.0], executor=ex)[0]
    assert e0.rows == e1.rows


def test_runs_of_a_lost_worker_are_reported_as_failed(short):
    """An executor whose worker died (a broken process pool) fails the task's future: its runs
    are reported as WorkerLost, which a study records as failed and reruns on resume."""
    from concurrent.futures import Executor, Future
    from concurrent.futures.process import BrokenProcessPool

    class Broken(Executor):
        def submit(self, fn, *args, **kwargs):
            f = Future()
            f.set_exception(BrokenProcessPool("a child process terminated abruptly"))
            return f

    seen = {}
    scaleout.run_cases([short.copy() for _ in range(3)], seen.__setitem__, executor=Broken(), chunk=2)
    assert sorted(seen) == [0, 1, 2] and all(isinstance(v, scaleout.WorkerLost) for v in seen.values())
    assert "BrokenProcessPool" in str(seen[0])
    sw = vtb.sweep(short, b_t=[5.0], k_t=[2e8], c_t=[1e3], executor=Broken(), progress=False)
    assert all("worker failed" in e for e in sw.columns["error"])


def test_a_local_cluster_runs_its_workers_with_the_study_settings():
    import dask

    def settings():
        return {k: dask.config.get(k) for k in scaleout.DASK_SETTINGS}

    with scaleout.local_cluster(1) as ex:
        on_worker = ex.submit(settings).result()
    assert on_worker == scaleout.DASK_SETTINGS != settings()  # this process keeps Dask's defaults
    # workers started by hand read the same settings from dask_environment()'s variables
    with dask.config.set(dask.config.collect_env(scaleout.dask_environment())):
        assert settings() == scaleout.DASK_SETTINGS


@pytest.mark.parametrize("n", [0, -2, 1.5, True, "2"])
def test_a_local_cluster_refuses_a_worker_count_that_is_not_a_whole_number_from_1(n):
    with pytest.raises(vtb.ConfigError, match="n_workers"):
        with scaleout.local_cluster(n):
            pass
