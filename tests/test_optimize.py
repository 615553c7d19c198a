"""vtb.optimize on a short case, and the calibrated article preset."""

from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import vtb
from vtb import optim as moga
from vtb.run import scaleout
from vtb.config.presets import ARTICLE_RAIL_ACC

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def result(short):
    return vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False)


def test_pareto_set_is_feasible_non_dominated_and_in_bounds(result):
    p, base = result.pareto, result.baseline
    assert len(result) >= 1
    for m in ("rail_acc_max", "slab_acc_max", "rail_acc_rms", "rail_acc_settle"):
        assert np.all(p[m] <= base[m]), m
    F = np.column_stack([p["rail_acc_max"], p["slab_acc_max"]])
    assert moga.non_dominated_sort(F)[0].size == len(F)
    assert np.all((p["b_t"] >= 1) & (p["b_t"] <= 10) & (p["k_t"] >= 1e7) & (p["k_t"] <= 8e8) & (p["c_t"] >= 10) & (p["c_t"] <= 5e3))
    np.testing.assert_allclose(p["eta_rail_acc_max"], (base["rail_acc_max"] - p["rail_acc_max"]) / base["rail_acc_max"])
    np.testing.assert_allclose(p["eta_r"], (p["eta_rail_acc_max"] + p["eta_rail_acc_rms"] + p["eta_rail_acc_settle"]) / 3)


def test_pareto_metrics_are_those_of_a_fresh_run(short, result):
    c = result.chosen("best η_r")
    cfg = vtb.article.tid_problem.case_config(short, c["b_t"], c["k_t"], c["c_t"])
    m = vtb.simulate(cfg).metrics()
    i = result.trade_offs()["best η_r"]
    assert result.pareto["rail_acc_max"][i] == m["rail_acc_max"]


def test_table_has_the_four_choices(result):
    rows = result.table()
    assert [r["choice"] for r in rows] == ["knee", "nearest to ideal", "ASF 0.5/0.5", "best η_r"]
    assert all(r["eta_r"] <= max(result.pareto["eta_r"]) for r in rows)


def test_same_seed_same_result_and_executor_identical(short, result):
    again = vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False)
    np.testing.assert_array_equal(again.pareto["k_t"], result.pareto["k_t"])
    with ProcessPoolExecutor(2) as ex:
        far = vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, executor=ex)
    np.testing.assert_array_equal(far.pareto["rail_acc_max"], result.pareto["rail_acc_max"])


def test_calibrated_preset_matches_the_article_rail_amplitude():
    """The one calibrated number (docs/reproduction.md)."""
    m = vtb.simulate(vtb.paper_config(calibrated=True)).metrics()
    assert m["rail_acc_max"] == pytest.approx(ARTICLE_RAIL_ACC, rel=0.005)


# --------------------------------------------------------------------------------------------
# Checkpoint, warm start, hypervolume stop
# --------------------------------------------------------------------------------------------

import inspect
import sys

from vtb import cli

from vtb.article import reproduce
from vtb.article.tid_optimize import warm_start_points
from vtb.article.tid_problem import tid_objectives

OPT = sys.modules["vtb.studies.optimize"]  # the module (vtb.optimize is the function)


class Killed(Exception):
    pass


def _same_optimisation(a, b):
    assert list(a.pareto) == list(b.pareto)
    for k in a.pareto:
        assert np.array_equal(a.pareto[k], b.pareto[k], equal_nan=True), k
    assert a.moga.history == b.moga.history and a.moga.n_evals == b.moga.n_evals
    assert np.array_equal(a.moga.pop.X, b.moga.pop.X) and np.array_equal(a.moga.pop.F, b.moga.pop.F)


def _batch_calls(monkeypatch, kill_at=None):
    """Counts the cases of each Rust batch of the optimiser; raises Killed at call ``kill_at``."""
    calls, real = [], scaleout.simulate_batch

    def counting(configs, **kw):
        calls.append(len(configs))
        if len(calls) == kill_at:
            raise Killed
        return real(configs, **kw)

    monkeypatch.setattr(scaleout, "simulate_batch", counting)
    return calls


def test_killed_optimisation_resumes_to_the_uninterrupted_result(short, result, tmp_path, monkeypatch):
    """Killed before evaluating generation 3, resumed from the checkpoint of generation 2: the
    Pareto set (metrics included) and the history are those of the uninterrupted run. Called
    again, the finished checkpoint and its designs journal give the same result without a run."""
    ck = tmp_path / "opt.npz"
    calls = _batch_calls(monkeypatch, kill_at=3)
    with pytest.raises(Killed):
        vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    calls = _batch_calls(monkeypatch)
    resumed = vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    assert 0 < calls[0] <= 8 and len(calls) == 1  # generation 3's designs not seen before
    _same_optimisation(result, resumed)
    calls.clear()
    again = vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    assert calls == []
    _same_optimisation(result, again)
    other = short.copy()
    other.speed = 70.0
    with pytest.raises(vtb.ConfigError, match="another optimisation") as e:  # its designs journal refuses first
        vtb.optimize(other, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    assert e.value.field == "checkpoint"


def _rewrite_stamp(ck, edit) -> None:
    """Rewrites the configuration stamp in a checkpoint and its designs journal by ``edit``
    (a stamp as an older or another vtb would have written it)."""
    import json

    with np.load(ck) as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(str(arrays["header"]))
    edit(header["identity"]["problem"]["vtb.optimize"]["config"])
    arrays["header"] = np.array(json.dumps(header))
    with open(ck, "wb") as f:
        np.savez(f, **arrays)
    journal = ck.with_name(ck.name + ".designs.jsonl")
    lines = journal.read_text().splitlines()
    first = json.loads(lines[0])
    edit(first["identity"]["vtb.optimize"]["config"])  # the header of a designs journal
    journal.write_text("\n".join([json.dumps(first), *lines[1:]]) + "\n")


def test_a_checkpoint_outlives_a_field_added_to_the_schema(short, result, tmp_path, monkeypatch):
    """A checkpoint whose stamp lacks a field added since (here ``irregularity.flat_shape``,
    as written before that field existed) resumes without a run: the stamp is read back through
    today's schema. One whose stamp holds another value (the speed) is refused."""
    ck = tmp_path / "opt.npz"
    vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    _rewrite_stamp(ck, lambda stamp: stamp["irregularity"].pop("flat_shape"))
    calls = _batch_calls(monkeypatch)
    again = vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    assert calls == []
    _same_optimisation(result, again)
    _rewrite_stamp(ck, lambda stamp: stamp.update(speed=70.0))
    with pytest.raises(vtb.StaleFileError, match="another optimisation"):
        vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)


def test_a_generation_killed_mid_batch_keeps_its_finished_designs(short, result, tmp_path, monkeypatch):
    """Killed inside generation 2's batch once three of its designs have finished: those three
    are in the designs journal, and the resumed run evaluates only the others."""
    ck = tmp_path / "opt.npz"
    journal = tmp_path / "opt.npz.designs.jsonl"
    real = scaleout.simulate_batch
    state = dict(batch=0)

    def killing(configs, **kw):
        state["batch"] += 1
        if state["batch"] == 2:
            seen = []

            def on_result(i, r, _inner=kw["on_result"]):
                _inner(i, r)
                seen.append(i)
                if len(seen) == 3:
                    raise Killed

            kw = dict(kw, on_result=on_result, threads=1)
        return real(configs, **kw)

    monkeypatch.setattr(scaleout, "simulate_batch", killing)
    with pytest.raises(Killed):
        vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    designs_before = len(journal.read_text().splitlines()) - 1  # the identity line
    assert designs_before >= 8 + 3  # generation 1, and three of generation 2
    calls = _batch_calls(monkeypatch)
    resumed = vtb.optimize(short, pop_size=8, n_gen=3, seed=3, progress=False, checkpoint=ck)
    assert calls[0] <= 8 - 3
    _same_optimisation(result, resumed)


def test_hypervolume_reference_is_the_uncontrolled_point(result):
    """The recorded hypervolume is that of the Pareto set's (a_rm, a_sm) against (a_rm0, a_sm0)."""
    p, b = result.pareto, result.baseline
    hv = moga.hypervolume_2d(np.c_[p["rail_acc_max"], p["slab_acc_max"]], (b["rail_acc_max"], b["slab_acc_max"]))
    assert hv > 0 and result.moga.history[-1].hypervolume == pytest.approx(hv, rel=1e-12)


def test_defaults_are_the_article_cold_budget():
    sig = inspect.signature(vtb.optimize).parameters
    assert (sig["pop_size"].default, sig["n_gen"].default) == (100, 100)
    assert sig["warm_start"].default is None and sig["stop_hv"].default is None
    args = cli.build_parser().parse_args(["optimize"])
    assert (args.pop, args.gen, args.warm_start, args.stop_hv, args.checkpoint) == (100, 100, None, None, None)


@pytest.fixture(scope="module")
def swept(short, tmp_path_factory):
    """A sweep journal of 6 TID cases, 4 within the optimiser's bounds (k_t = 1e9 is not)."""
    out = tmp_path_factory.mktemp("warm") / "sweep.csv"
    vtb.sweep(short, b_t=[2.0, 5.0], k_t=[1e8, 2e8, 1e9], c_t=[1e3], out=out, progress=False)
    return out


def test_warm_start_points_are_what_the_evaluator_computes(short, result, swept):
    X, F, G, metrics = warm_start_points(swept, short, result.baseline)
    assert len(X) == 6
    inside = X[:, 1] <= 8e8
    F_run, G_run = tid_objectives(short, result.baseline)(X[inside])
    assert np.array_equal(F[inside], F_run) and np.array_equal(G[inside], G_run)
    assert [m["rail_acc_max"] for m in metrics] == list(F[:, 0])


def test_a_warm_start_does_not_depend_on_the_journals_line_order(short, result, swept, tmp_path):
    """A journal whose cases were written in another order (a resumed or parallel sweep) gives
    the same warm-start points, in (b_t, k_t, c_t) order, as the sweep that ran in grid order."""
    lines = swept.read_text().splitlines()
    stamp, header, rows = lines[0], lines[1], lines[2:]
    shuffled = tmp_path / "shuffled.csv"
    shuffled.write_text("\n".join([stamp, header, *rows[::-1]]) + "\n")
    in_order = warm_start_points(vtb.article.tid_problem.read_journal(swept), short, result.baseline)
    reversed_ = warm_start_points(shuffled, short, result.baseline)
    for a, b in zip(in_order[:3], reversed_[:3]):
        assert np.array_equal(a, b)
    X = in_order[0]
    assert [tuple(x) for x in X] == sorted(tuple(x) for x in X)


def test_warm_started_optimisation_uses_the_sweep(short, swept, monkeypatch):
    """Population 6 from the 4 sweep cases within the bounds plus 2 random points (the only
    runs of generation 1); sweep cases reach the Pareto set with the sweep's metrics, not run
    again; a SweepResult and its journal give the same run."""
    calls = _batch_calls(monkeypatch)
    a = vtb.optimize(short, pop_size=6, n_gen=2, seed=0, progress=False, warm_start=swept)
    assert a.moga.history[0].n_evals == 2 and calls[0] == 2 and a.moga.n_evals == 2 + 6
    assert np.any((a.pareto["k_t"] == 1e8) & (a.pareto["c_t"] == 1e3))  # a sweep case on the front
    assert sum(calls) == a.moga.n_evals
    b = vtb.optimize(short, pop_size=6, n_gen=2, seed=0, progress=False, warm_start=vtb.article.tid_problem.read_journal(swept))
    _same_optimisation(a, b)


def test_warm_start_of_another_configuration_or_a_bad_journal_is_refused(short, swept, tmp_path):
    other = short.copy()
    other.speed = 70.0
    with pytest.raises(vtb.ConfigError, match="another configuration") as e:
        vtb.optimize(other, pop_size=4, n_gen=1, progress=False, warm_start=swept)
    assert e.value.field == "warm_start"
    bad = tmp_path / "bad.csv"
    lines = swept.read_text().splitlines(keepends=True)
    bad.write_text("".join(lines[:3]) + "1,2\n")
    with pytest.raises(vtb.ConfigError, match="line 4") as e:
        vtb.optimize(short, pop_size=4, n_gen=1, progress=False, warm_start=bad)
    assert e.value.field == "warm_start"


def test_a_journal_computed_by_other_numerics_is_stale(short, swept):
    """A journal whose uncontrolled run no longer equals a fresh one (written by another vtb
    version) is a StaleFileError naming the journal, which --force sets aside and reruns; the
    same sweep held in memory only is a plain ConfigError."""
    sw = vtb.article.tid_problem.read_journal(swept)
    assert sw.journal == str(swept)
    sw.columns["rail_acc_max"][0] *= 1.0 + 1e-12  # the baseline of other numerics
    with pytest.raises(vtb.StaleFileError, match="differs") as e:
        vtb.optimize(short, pop_size=4, n_gen=1, progress=False, warm_start=sw)
    assert e.value.path == str(swept)
    sw.journal = None
    with pytest.raises(vtb.ConfigError, match="differs") as e:
        vtb.optimize(short, pop_size=4, n_gen=1, progress=False, warm_start=sw)
    assert not isinstance(e.value, vtb.StaleFileError)


def test_optimize_command_warm_start_stop_and_checkpoint(short, tmp_path, capsys):
    """vtb sweep, then vtb optimize warm-started from its journal with a checkpoint; the same
    command again finds the finished checkpoint and evaluates nothing."""
    cfg = tmp_path / "short.toml"
    short.to_toml(cfg)
    journal, ck = tmp_path / "s.csv", tmp_path / "opt.npz"
    assert cli.main(["sweep", "--config", str(cfg), "--b", "5", "--k", "1e8,2e8", "--c", "1000", "--out", str(journal), "--no-progress"]) == 0
    command = ["optimize", "--config", str(cfg), "--pop", "4", "--gen", "2", "--warm-start", str(journal), "--stop-hv", "1e-3", "3", "--checkpoint", str(ck), "--no-progress"]
    capsys.readouterr()
    assert cli.main(command) == 0
    first = capsys.readouterr().out
    assert "# 2 generations, 6 evaluations (reached n_gen = 2)" in first
    assert cli.main(command) == 0
    assert capsys.readouterr().out == first
    assert cli.main(["optimize", "--config", str(cfg), "--pop", "4", "--gen", "2", "--stop-hv", "1e-3", "2.5", "--no-progress"]) == 2
    assert "stop_hv" in capsys.readouterr().err


def test_reproduction_records_hypervolume_against_evaluations(short, swept, tmp_path):
    """The reproduction's optimisation step, both runs: its CSV holds every generation's
    evaluations and hypervolume of each run, the warm run's first generation free."""
    import csv

    sw = vtb.article.tid_problem.read_journal(swept)
    runs = reproduce.optimisations(short, sw, tmp_path, dict(pop_size=4, n_gen=2), seed=0, optimiser="both", progress=False)
    with open(tmp_path / "optimisation_history.csv") as f:
        rows = list(csv.DictReader(f))
    expected = [(label, h) for label in ("warm", "cold") for h in runs[label][0].moga.history]
    assert [(r["run"], int(r["gen"]), int(r["n_evals"]), float(r["hypervolume"])) for r in rows] == [
        (label, h.gen, h.n_evals, h.hypervolume) for label, h in expected
    ]
    assert [int(r["n_evals"]) for r in rows] == [0, 4, 4, 8]
    with pytest.raises(vtb.ConfigError, match="optimiser"):
        reproduce.optimisations(short, sw, tmp_path, dict(pop_size=4, n_gen=2), optimiser="lukewarm")


def _optimiser_choice_bench():
    import importlib.util

    spec = importlib.util.spec_from_file_location("optimiser_choice", ROOT / "benches" / "optimiser_choice.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    return bench


def test_the_optimiser_rule_decides_before_the_last_runs_only_when_they_cannot_change_it():
    """The bench's rule: the higher median final hypervolume over 5 seeds, a tie (0.5 %) broken
    by the fewer median evaluations; with runs missing, a verdict only when every result of the
    missing runs gives the same one."""
    bench = _optimiser_choice_bench()

    def runs(start, hvs, evals=10_000):
        return [dict(start=start, seed=i, hypervolume=h, evaluations=evals) for i, h in enumerate(hvs)]

    cold = runs("cold", [300, 310, 320, 330, 340])
    # warm's median is at most 120 whatever its fifth seed reaches: cold already wins.
    assert bench.verdict(cold + runs("warm", [100, 110, 120, 130]), 5) == "cold"
    # a fifth warm seed above 400 would put warm's median at 400: undecided.
    assert bench.verdict(cold + runs("warm", [100, 110, 400, 410]), 5) is None
    assert bench.verdict(cold + runs("warm", [100, 110, 400, 410, 420]), 5) == "warm"
    # within 0.5 %: the fewer evaluations decide, and only once every seed is in.
    assert bench.verdict(cold + runs("warm", [320.5] * 5, evals=6_000), 5) == "warm"
    assert bench.verdict(cold + runs("warm", [320.5] * 4, evals=6_000), 5) is None
    assert bench.verdict(runs("cold", [300, 310]) + runs("warm", [100, 110, 120, 130]), 5) is None


def test_the_stop_table_finds_where_each_tolerance_would_have_stopped():
    """The bench's stop table replays the optimiser's own stop test: hypervolume 100, 110, …
    up to 200 at generation 11, then flat. Over a window of 10 generations the test looks at the
    last 11 values: at generation 19 they span 180–200 (10 % of 200), at 20 190–200 (5 %), at
    21 nothing. So a tolerance of 0.11 stops at 19, 0.06 at 20, 1e-3 at 21."""
    bench = _optimiser_choice_bench()
    hv = [100.0 + 10 * g for g in range(11)] + [200.0] * 15
    history = [[100 * (g + 1), h] for g, h in enumerate(hv)]
    assert bench.stopped_at(history, 1e-3, 10) == (21, 2100, 200.0)
    assert bench.stopped_at(history[:20], 1e-3, 10) is None
    assert bench.stopped_at(history, 0.06, 10) == (20, 2000, 200.0)
    assert bench.stopped_at(history, 0.11, 10) == (19, 1900, 200.0)


def test_the_reproductions_default_optimiser_is_the_one_the_seeds_chose():
    """docs/optimiser-choice/runs.json holds the cold and warm runs over seeds
    (``python benches/optimiser_choice.py``); the rule of that bench picks the default, and
    the reproduction and the CLI use it."""
    import json

    bench = _optimiser_choice_bench()
    runs = json.loads((ROOT / "docs" / "optimiser-choice" / "runs.json").read_text())
    for r in runs:  # every record is a whole run of the stated budget, its history consistent
        assert r["history"][-1] == [r["evaluations"], r["hypervolume"]] and len(r["history"]) == r["generations"] <= bench.N_GEN
    chosen = bench.verdict(runs, n_seeds=5)
    if chosen is None:
        done = {s: sum(r["start"] == s for r in runs) for s in bench.STARTS}
        pytest.skip(f"the evidence is incomplete ({done} of 5 seeds); the default stays {reproduce.DEFAULT_OPTIMISER!r}")
    assert reproduce.DEFAULT_OPTIMISER == chosen
    assert cli.build_parser().parse_args(["reproduce", "--out", "rep"]).optimiser == chosen


def test_a_stamp_is_compared_through_todays_schema(short):
    """vtb.studies.journal.same_config: a stamp lacking a field added since is the same configuration;
    one holding another value, or one that no longer parses, is not."""
    import json

    from vtb.studies.journal import config_stamp, same_config

    stamp = json.loads(config_stamp(short))
    assert same_config(json.dumps(stamp), short)
    del stamp["irregularity"]["flat_shape"]
    assert same_config(stamp, short)
    assert not same_config(dict(stamp, speed=short.speed + 1.0), short)
    assert not same_config(dict(stamp, no_such_field=1), short)
    assert not same_config("0123abcd", short)  # the hash an older checkpoint stored
