"""Designs over irregularity samples and speeds (vtb.robust): the statistics against their
definitions, and the out-of-sample evaluator against single runs of the same cases."""

import math

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config
from vtb import robust


def test_statistics_and_the_standard_error_follow_their_definitions():
    v = [1.0, 2.0, 3.0, 4.0]
    assert robust.statistic(v, "mean") == 2.5
    assert robust.statistic(v, "max") == 4.0 and robust.statistic(v, "min") == 1.0
    assert robust.statistic(v, "median") == 2.5 == robust.statistic(v, "p50")
    assert robust.statistic(v, "p90") == pytest.approx(3.7)  # 1 + 0.9·3 order-statistic steps
    assert robust.standard_error(v) == pytest.approx(math.sqrt(5 / 3) / 2)  # s = √(5/3), N = 4
    assert math.isnan(robust.standard_error([1.0]))
    for bad in ("p0", "p100", "average", 90):
        with pytest.raises(vtb.ConfigError) as e:
            robust.statistic(v, bad)
        assert e.value.field == "statistic"


def test_seeds_are_documented_and_checked():
    assert robust.seeds(3, robust.HELD_OUT_SEED0) == [2000, 2001, 2002]
    assert robust.seeds([5, 9], 0) == [5, 9]
    for bad in (0, -2, [1, 1], [], [1.5], True):
        with pytest.raises(vtb.ConfigError) as e:
            robust.seeds(bad, 0)
        assert e.value.field == "samples"


def _config():
    cfg = small_config(tids=True)
    cfg.solver.t_end = None  # the whole passage, so the irregularity is felt at the observation point
    return cfg


def test_evaluate_design_matches_single_runs_of_the_same_cases():
    cfg = _config()
    design = dict(b_t=5.0, k_t=2e8, c_t=1e3)
    ev = vtb.evaluate_design(cfg, design, samples=[3, 4], speeds=[70.0, 80.0])
    assert [(r["speed"], r["seed"]) for r in ev.rows] == [(70.0, 3), (70.0, 4), (80.0, 3), (80.0, 4)]
    feasible = []
    for row in ev.rows:
        one = cfg.copy()
        one.speed = row["speed"]
        one.irregularity.seed = row["seed"]
        unc = one.copy()
        unc.tids = None
        m0, m1 = vtb.simulate(unc).metrics(), vtb.simulate(one).metrics()
        assert row["rail_acc_max_0"] == m0["rail_acc_max"] and row["slab_acc_max"] == m1["slab_acc_max"]
        assert row["eta_rail_acc_max"] == pytest.approx((m0["rail_acc_max"] - m1["rail_acc_max"]) / m0["rail_acc_max"], rel=1e-12)
        feasible.append(all(m1[k] <= m0[k] for k in ("rail_acc_max", "slab_acc_max", "rail_acc_rms", "rail_acc_settle")))
    assert ev.satisfaction_rate == np.mean(feasible)
    s = ev.summary("p90")
    eta = ev.column("eta_rail_acc_max")
    assert s["eta_rail_acc_max"] == (pytest.approx(np.quantile(eta, 0.9)), pytest.approx(eta.mean()), pytest.approx(eta.std(ddof=1) / 2))
    assert ev.summary(speed=80.0)["eta_rail_acc_max"][1] == pytest.approx(eta[2:].mean())
    # the samples differ: a design is not judged on one realisation
    assert len(set(ev.column("rail_acc_max_0"))) == 4


def test_evaluate_design_refuses_what_it_cannot_sample():
    cfg = _config()
    with pytest.raises(vtb.ConfigError) as e:
        vtb.evaluate_design(cfg, dict(b_t=5.0, k_t=2e8), samples=2)
    assert e.value.field == "design"
    with pytest.raises(vtb.ConfigError) as e:
        vtb.evaluate_design(cfg, dict(b_t=5.0, k_t=2e8, c_t=1e3), samples=2, speeds=[80.0, -1.0])
    assert e.value.field == "speeds"
    cfg.irregularity = vtb.Irregularity(kind="none")
    with pytest.raises(vtb.ConfigError) as e:
        vtb.evaluate_design(cfg, dict(b_t=5.0, k_t=2e8, c_t=1e3), samples=2)
    assert e.value.field == "irregularity.kind"
