"""vtb.optimize on a short case, and the calibrated article preset."""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import vtb
from vtb import moga
from vtb.presets import ARTICLE_RAIL_ACC


@pytest.fixture(scope="module")
def short():
    c = vtb.paper_config()
    c.solver.t_end = 0.15
    c.output.points = [8.0]
    c.tids = vtb.tids_around(c, count=2, x=8.0)
    return c


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
    cfg = vtb.tid_sweep.case_config(short, c["b_t"], c["k_t"], c["c_t"])
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
