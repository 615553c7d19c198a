"""The TID sweep: parallel paths give identical results, nothing is lost, analyses by hand."""

import math
from pathlib import Path
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import vtb
from vtb.run import scaleout
from vtb.studies import grid as studies_mod
from vtb.article import tid_problem, tid_sweep
from vtb.article.tid_problem import COLUMNS, SweepResult
from vtb.run.indices import METRICS

GRID = dict(b_t=[2.0, 5.0], k_t=[1e8, 2e8], c_t=[1e3])


@pytest.fixture(scope="module")
def reference(short):
    return vtb.sweep(short, **GRID, progress=False)


def _same(a, b):
    assert len(a) == len(b)
    for k in COLUMNS:
        if k == "error":
            assert list(a.columns[k]) == list(b.columns[k])
        else:
            np.testing.assert_array_equal(a.columns[k], b.columns[k])


def _same_rows(a, b):
    """`_same` up to the order of the rows: a journal numbers its cases in the order they
    finished, which threads make vary."""
    assert len(a) == len(b)

    def rows(r):
        c = r.columns
        key = lambda i: tuple((0.0, -1.0) if math.isnan(c[p][i]) else (1.0, c[p][i]) for p in ("b_t", "k_t", "c_t"))
        order = sorted(range(len(r)), key=key)
        return {k: [c[k][i] for i in order] for k in COLUMNS if k != "case"}

    ra, rb = rows(a), rows(b)
    for k in ra:
        if k == "error":
            assert ra[k] == rb[k]
        else:
            np.testing.assert_array_equal(np.asarray(ra[k], float), np.asarray(rb[k], float))


def test_grid_and_baseline(reference, short):
    c = reference.columns
    assert list(c["case"]) == [0, 1, 2, 3, 4]
    assert math.isnan(c["b_t"][0]) and list(c["b_t"][1:]) == [2.0, 2.0, 5.0, 5.0]
    assert all(e == "" for e in c["error"])
    base = vtb.simulate(tid_problem.case_config(short, math.nan, 0, 0)).metrics()
    assert reference.baseline["rail_acc_max"] == base["rail_acc_max"]
    one = vtb.simulate(tid_problem.case_config(short, 5.0, 2e8, 1e3)).metrics()
    assert c["rail_acc_max"][4] == one["rail_acc_max"]


def test_article_grid_has_1840_cases():
    assert len(tid_problem.grid(tid_sweep.ARTICLE_B, tid_sweep.ARTICLE_K, tid_sweep.ARTICLE_C)) == 1840
    assert tid_sweep.ARTICLE_K[:3] == (1e4, 2e4, 3e4) and tid_sweep.ARTICLE_K[-2:] == (9e8, 1e9)


def test_process_pool_gives_identical_results(short, reference):
    with ProcessPoolExecutor(2) as ex:
        _same(reference, vtb.sweep(short, **GRID, executor=ex, chunk=2, progress=False))


def test_dask_cluster_gives_identical_results(short, reference):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            _same(reference, vtb.sweep(short, **GRID, executor=client.get_executor(), chunk=2, progress=False))


def interrupted_then_resumed(config, grid, out, monkeypatch):
    """A sweep killed (Ctrl-C) after its first lockstep group is journaled, then resumed: the
    cases journaled before the kill, the runs of every later batch call (a list the caller
    may clear) and the resumed result."""
    ran = []
    real = scaleout.simulate_batch

    def counting(configs, **kw):
        ran.append(len(configs))
        return real(configs, **kw)

    monkeypatch.setattr(scaleout, "simulate_batch", counting)

    def kill(done, total):
        assert 0 < done < total, "a kill mid-way needs more than one lockstep group"
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        vtb.sweep(config, **grid, out=out, progress=kill, threads=1)
    rows = [line for line in Path(out).read_text().splitlines()[2:] if line.strip()]
    ran.clear()
    resumed = vtb.sweep(config, **grid, out=out, progress=False, threads=1)
    return len(rows), ran, resumed


def test_killed_sweep_resumes_without_recomputing(short, reference, tmp_path, monkeypatch):
    out = tmp_path / "sweep.csv"
    n_cases = len(reference)
    journaled, ran, resumed = interrupted_then_resumed(short, GRID, out, monkeypatch)
    assert 0 < journaled < n_cases
    assert sum(ran) == n_cases - journaled  # nothing finished runs again
    _same(reference, resumed)  # bit for bit
    # A line cut short by a kill is ignored, and a finished sweep runs nothing.
    with open(out, "a") as f:
        f.write("3,5.0,1e8")
    ran.clear()
    again = vtb.sweep(short, **GRID, out=out, progress=False)
    assert sum(ran) == 0
    _same(reference, again)


def test_failed_cases_are_recorded_and_the_sweep_goes_on(short):
    bad = short.copy()
    bad.solver.contact_max_iter = 1
    bad.solver.contact_tol = 1e-300
    r = vtb.sweep(bad, b_t=[5.0], k_t=[2e8], c_t=[1e3], progress=False)
    assert len(r) == 2
    assert all("ConvergenceError" in e for e in r.columns["error"])
    assert np.isnan(r.columns["rail_acc_max"]).all()


def test_exports(reference, tmp_path):
    pd = pytest.importorskip("pandas")
    reference.to_csv(tmp_path / "a.csv")
    back = pd.read_csv(tmp_path / "a.csv", keep_default_na=False, na_values=["nan"])
    np.testing.assert_array_equal(back["rail_acc_max"].to_numpy(), reference.columns["rail_acc_max"])
    pytest.importorskip("pyarrow")
    reference.to_parquet(tmp_path / "a.parquet")
    df = pd.read_parquet(tmp_path / "a.parquet")
    np.testing.assert_array_equal(df["k_t"].to_numpy(), reference.columns["k_t"])
    assert list(reference.to_pandas().columns) == list(COLUMNS)


def test_parquet_output_path_keeps_a_csv_journal(short, tmp_path):
    pytest.importorskip("pyarrow")
    out = tmp_path / "s.parquet"
    vtb.sweep(short, b_t=[5.0], k_t=[2e8], c_t=[1e3], out=out, progress=False)
    assert out.exists() and (tmp_path / "s.parquet.csv").exists()


def test_bad_grid_names_the_field(short):
    with pytest.raises(vtb.ConfigError, match="b_t"):
        vtb.sweep(short, b_t=[-1.0], progress=False)
    with pytest.raises(vtb.ConfigError, match="c_t"):
        vtb.sweep(short, c_t=[], progress=False)


def _synthetic():
    """Two inertances, two stiffnesses; numbers chosen by hand."""
    rows = [
        (0, math.nan, math.nan, math.nan, 100.0, 10.0, 1.0, 40.0),
        (1, 1.0, 1e6, 10.0, 90.0, 9.0, 0.9, 42.0),
        (2, 1.0, 4e6, 10.0, 95.0, 9.5, 1.0, 39.0),
        (3, 4.0, 1e6, 10.0, 99.0, 10.0, 1.0, 41.0),
        (4, 4.0, 4e6, 10.0, 80.0, 8.0, 0.8, 45.0),
    ]
    cols = {k: np.full(len(rows), 0.0) for k in COLUMNS if k != "error"}
    for j, r in enumerate(rows):
        for k, v in zip(("case", "b_t", "k_t", "c_t", "rail_acc_max", "rail_acc_rms", "rail_acc_settle", "slab_acc_max"), r):
            cols[k][j] = v
    cols["case"] = cols["case"].astype(int)
    cols["error"] = np.array([""] * len(rows))
    return SweepResult(columns=cols, config=vtb.paper_config())


def test_analyses_by_hand():
    s = _synthetic()
    t = s.best_per_inertance()
    assert list(t["k_t"]) == [1e6, 4e6]
    np.testing.assert_allclose(t["eta_rail_acc_max"], [0.10, 0.20])
    np.testing.assert_allclose(t["eta_r"], [(0.1 + 0.1 + 0.1) / 3, (0.2 + 0.2 + 0.2) / 3])
    np.testing.assert_allclose(t["slab_increase"], [2.0, 5.0])
    np.testing.assert_allclose(t["slab_acc_min"], [39.0, 41.0])
    np.testing.assert_allclose(t["working_frequency"], [math.sqrt(1e6) / (2 * math.pi), math.sqrt(1e6) / (2 * math.pi)])
    assert s.best()["b_t"] == 4.0 and s.best()["eta_rail_acc_max"] == pytest.approx(0.2)
    w = s.worst_slab_increase()
    assert w["b_t"] == 4.0 and w["increase"] == 5.0 and w["relative"] == pytest.approx(5.0 / 40.0)


def test_pinned_pinned_frequency_of_the_article_rail():
    """CHN60 (EI = 2.1e11·3.217e-5, ρA = 7800·7.745e-3) on d = 0.64 m: (π/d)²·sqrt(EI/ρA)/2π."""
    f = vtb.pinned_pinned_frequency(vtb.paper_config())
    assert f == pytest.approx((math.pi / 0.64) ** 2 * math.sqrt(2.1e11 * 3.217e-5 / (7800 * 7.745e-3)) / (2 * math.pi))
    assert 1200 < f < 1350


def test_journal_of_another_configuration_is_refused(short, tmp_path):
    out = tmp_path / "s.csv"
    vtb.sweep(short, b_t=[5.0], k_t=[2e8], c_t=[1e3], out=out, progress=False)
    other = short.copy()
    other.speed = 70.0
    with pytest.raises(vtb.ConfigError, match="another configuration"):
        vtb.sweep(other, b_t=[5.0], k_t=[2e8], c_t=[1e3], out=out, progress=False)


def test_changed_grid_reruns_cases_whose_parameters_differ(short, tmp_path, monkeypatch):
    out = tmp_path / "s.csv"
    vtb.sweep(short, b_t=[5.0], k_t=[2e8], c_t=[1e3], out=out, progress=False)
    ran = _recording(monkeypatch)
    r = vtb.sweep(short, b_t=[5.0], k_t=[1e8], c_t=[1e3], out=out, progress=False)
    assert ran == [(5.0, 1e8, 1e3)] and r.columns["k_t"][1] == 1e8


def test_analyses_refuse_a_sweep_without_successes():
    s = _synthetic()
    s.columns["error"] = np.array(["x"] * len(s))
    with pytest.raises(vtb.VtbError):
        s.best()


# --------------------------------------------------------------------------------------------
# Journal integrity
# --------------------------------------------------------------------------------------------

ONE = dict(b_t=[5.0], k_t=[2e8], c_t=[1e3])


def _recording(monkeypatch):
    """Records the (b_t, k_t, c_t) of every case run (None for the baseline)."""
    ran = []
    real = studies_mod.run_cases

    def recording(configs, on_result, **kw):
        ran.extend(None if c.tids is None else (c.tids.inertance, c.tids.stiffness, c.tids.damping) for c in configs)
        return real(configs, on_result, **kw)

    monkeypatch.setattr(studies_mod, "run_cases", recording)
    return ran


@pytest.fixture(scope="module")
def journal_lines(short, tmp_path_factory):
    """The lines of a valid journal of ONE: stamp, header, baseline row, one TID row (rows
    are journaled as runs finish, in either order; a journal's row order carries no meaning)."""
    out = tmp_path_factory.mktemp("journal") / "s.csv"
    vtb.sweep(short, **ONE, out=out, progress=False)
    lines = out.read_text().splitlines(keepends=True)
    return lines[:2] + sorted(lines[2:], key=lambda row: not row.startswith("nan,"))


def test_journal_carries_its_configuration_and_nothing_else(short, journal_lines, tmp_path):
    import json

    stamp = journal_lines[0]
    assert stamp.startswith("# vtb sweep journal ")
    body = json.loads(stamp[len("# vtb sweep journal "):])
    assert body["format"] == 1 and body["config"] == short.to_dict()
    assert journal_lines[1].strip() == ",".join(tid_problem.JOURNAL_COLUMNS)
    assert len(journal_lines) == 4
    out = tmp_path / "s.csv"
    vtb.sweep(short, **ONE, out=out, progress=False)
    assert [p.name for p in tmp_path.iterdir()] == ["s.csv"]  # no side file, the lock is gone


def test_extended_grid_reruns_only_the_new_cases(short, reference, tmp_path, monkeypatch):
    """A journal of b_t = 5, k_t = 2e8 (there case 1) extended to GRID (where it is case 4):
    only the three new parameter sets run and the result is the fresh sweep's."""
    out = tmp_path / "s.csv"
    vtb.sweep(short, **ONE, out=out, progress=False)
    ran = _recording(monkeypatch)
    extended = vtb.sweep(short, **GRID, out=out, progress=False)
    assert sorted(ran) == [(2.0, 1e8, 1e3), (2.0, 2e8, 1e3), (5.0, 1e8, 1e3)]
    _same(reference, extended)
    ran.clear()
    back = vtb.sweep(short, **ONE, out=out, progress=False)  # the smaller grid again: all reused
    assert ran == [] and list(back.columns["case"]) == [0, 1] and back.columns["k_t"][1] == 2e8


def test_failed_cases_are_retried_on_resume(short, reference, tmp_path, monkeypatch):
    out = tmp_path / "s.csv"
    real = studies_mod.run_cases

    def failing(configs, on_result, **kw):
        def altered(i, r):
            t = configs[i].tids
            made_up = t is not None and (t.inertance, t.stiffness) == (5.0, 1e8)
            on_result(i, vtb.ConvergenceError("made up") if made_up else r)

        real(configs, altered, **kw)

    monkeypatch.setattr(studies_mod, "run_cases", failing)
    first = vtb.sweep(short, **GRID, out=out, progress=False)
    assert list(first.columns["error"]).count("ConvergenceError: made up") == 1
    monkeypatch.undo()
    ran = _recording(monkeypatch)
    second = vtb.sweep(short, **GRID, out=out, progress=False)
    assert ran == [(5.0, 1e8, 1e3)]
    _same(reference, second)
    ran.clear()
    vtb.sweep(short, **GRID, out=out, progress=False)
    assert ran == []
    # the journal keeps both rows; the successful one is the case's
    assert sum(line.startswith("5.0,100000000.0,") for line in out.read_text().splitlines()) == 2
    _same_rows(reference, tid_problem.read_journal(out))


def test_repeated_rows_the_last_successful_one_wins(short, journal_lines, tmp_path, monkeypatch):
    """Two successful rows of one key: the later counts; a failed row after them changes
    nothing (and triggers no re-run); only failures of a key make it run again."""
    row = journal_lines[3].split(",")
    later = ",".join([*row[:3], "123.0", *row[4:]])
    failed = ",".join([*row[:3]] + ["nan"] * len(METRICS) + ["SolverError: made up\n"])
    out = tmp_path / "s.csv"
    out.write_text("".join(journal_lines) + later + failed)
    ran = _recording(monkeypatch)
    r = vtb.sweep(short, **ONE, out=out, progress=False)
    assert ran == [] and r.columns["rail_acc_max"][1] == 123.0 and r.columns["error"][1] == ""
    out.write_text("".join(journal_lines[:3]) + failed + failed)
    r = vtb.sweep(short, **ONE, out=out, progress=False)
    assert ran == [(5.0, 2e8, 1e3)] and r.columns["error"][1] == ""
    assert r.columns["rail_acc_max"][1] == float(row[3])


def _corrupt(lines, number, new):
    lines = list(lines)
    lines[number - 1] = new
    return "".join(lines)


CORRUPTIONS = {
    "wrong header": (2, lambda L: _corrupt(L, 2, L[1].replace("rail_acc_max", "rail_acc_mx"))),
    "non-numeric value": (4, lambda L: _corrupt(L, 4, L[3].replace(L[3].split(",")[4], "fast", 1))),
    "missing field": (3, lambda L: _corrupt(L, 3, L[2].split(",", 1)[1])),
    "extra field": (4, lambda L: _corrupt(L, 4, "1.0," + L[3])),
    "half a baseline key": (4, lambda L: _corrupt(L, 4, "nan," + L[3].split(",", 1)[1])),
    "stamp does not parse": (1, lambda L: _corrupt(L, 1, L[0][:200] + "\n")),
    "stamp of a bad config": (1, lambda L: _corrupt(L, 1, L[0].replace('"speed": 80.0', '"speed": "fast"'))),
    "no stamp (old journal)": (1, lambda L: "".join(L[1:])),
    "not a journal": (1, lambda L: "hello\nworld\n"),
}


@pytest.mark.parametrize("kind", list(CORRUPTIONS))
def test_corrupt_journal_is_refused_with_its_line(short, journal_lines, tmp_path, monkeypatch, kind):
    number, corrupt = CORRUPTIONS[kind]
    out = tmp_path / "s.csv"
    out.write_text(corrupt(journal_lines))
    before = out.read_bytes()
    ran = _recording(monkeypatch)
    with pytest.raises(vtb.ConfigError, match=f"line {number}:") as e:
        vtb.sweep(short, **ONE, out=out, progress=False)
    assert e.value.field == "out" and str(out) in str(e.value)
    assert ran == [] and out.read_bytes() == before
    with pytest.raises(vtb.ConfigError, match=f"line {number}:"):
        tid_problem.read_journal(out)


def test_partial_last_line_is_still_dropped(short, journal_lines, tmp_path, monkeypatch):
    out = tmp_path / "s.csv"
    out.write_text("".join(journal_lines[:3]) + journal_lines[3][:40])
    assert len(tid_problem.read_journal(out)) == 1  # a reader ignores it without touching the file
    ran = _recording(monkeypatch)
    r = vtb.sweep(short, **ONE, out=out, progress=False)
    assert ran == [(5.0, 2e8, 1e3)] and r.columns["error"][1] == ""
    assert out.read_text() == "".join(journal_lines)


_HOLDER = """
import sys, time
from pathlib import Path
from vtb.studies.journal import lock
with lock(Path(sys.argv[1])):
    print("locked", flush=True)
    time.sleep(120)
"""


def test_a_second_sweep_on_a_journal_in_use_is_refused(short, tmp_path):
    """Another process holds the journal's lock: the sweep is refused naming ``out`` and the
    holder's pid. Killed (SIGKILL, no clean-up), the holder leaves its lock file, which no
    longer blocks: the kernel released the lock with the process."""
    import os
    import subprocess
    import sys

    out = tmp_path / "s.csv"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(vtb.__file__).parents[1]), os.environ.get("PYTHONPATH", "")]))
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out)], stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert holder.stdout.readline() == "locked\n"
        with pytest.raises(vtb.ConfigError, match=f"pid {holder.pid} ") as e:
            vtb.sweep(short, **ONE, out=out, progress=False)
        assert e.value.field == "out" and "another sweep" in str(e.value)
    finally:
        holder.kill()
        holder.wait()
    lock = tmp_path / "s.csv.lock"
    assert lock.read_text().startswith(f"pid {holder.pid} ")  # the stale lock file, with its pid
    r = vtb.sweep(short, **ONE, out=out, progress=False)
    assert r.columns["error"][1] == "" and not lock.exists()
