"""Designs over irregularity samples and speeds (vtb.robust): the statistics against their
definitions, and the out-of-sample evaluator against single runs of the same cases."""

import math

import numpy as np
import pytest

import vtb
from fuzz_cases import small_config
from vtb.article import robust
from vtb.run import scaleout


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


def test_design_statistics_follow_their_definitions():
    # two cases, one feasible, with ratios X/X0 written out by hand
    rows = []
    for a0, a, s0, s in ((100.0, 80.0, 10.0, 12.0), (200.0, 150.0, 20.0, 18.0)):
        m0 = {m: 1.0 for m in robust.METRICS}
        m1 = dict(m0)
        m0.update(rail_acc_max=a0, slab_acc_max=s0)
        m1.update(rail_acc_max=a, slab_acc_max=s)
        rows.append(robust._case_row(80.0, 0, m0, m1))
    st = robust.design_statistics(rows, "max")
    assert st["ratio_rail_acc_max"] == pytest.approx(0.8) and st["mean_rail_acc_max"] == pytest.approx(0.775)
    assert st["sem_rail_acc_max"] == pytest.approx(0.025)  # s = 0.025·√2, N = 2
    assert st["ratio_slab_acc_max"] == pytest.approx(1.2) and st["satisfaction_rate"] == 0.5
    assert st["feasible"] is False  # the worst case raises the slab: max(a_sm/a_sm0) = 1.2 > 1
    F, G = robust.robust_objectives(rows, "mean")
    assert F == pytest.approx([0.775, 1.05]) and G == pytest.approx([-0.225, 0.05, 0.0, 0.0])
    failed = rows + [robust._case_row(80.0, 1, None, None, "ConvergenceError: x")]
    assert robust.robust_objectives(failed, "mean") == ([10.0, 10.0], [math.inf] * 4)
    assert robust.design_statistics(failed, "mean")["feasible"] is False


def test_robust_sweep_cases_are_the_out_of_sample_evaluator_on_the_design_seeds(tmp_path):
    cfg = _config()
    rs = vtb.sweep(cfg, [2.0, 5.0], [2e8], [1e3], samples=2, speeds=[70.0, 80.0], statistic="p90", out=tmp_path, progress=False)
    assert isinstance(rs, robust.RobustSweep) and rs.designs == [(2.0, 2e8, 1e3), (5.0, 2e8, 1e3)]
    assert sorted(p.name for p in tmp_path.glob("*.csv")) == ["v70_seed1000.csv", "v70_seed1001.csv", "v80_seed1000.csv", "v80_seed1001.csv"]
    table = rs.table()
    for i, (b, k, c) in enumerate(rs.designs):
        ev = vtb.evaluate_design(cfg, dict(b_t=b, k_t=k, c_t=c), samples=2, speeds=[70.0, 80.0], first_seed=robust.DESIGN_SEED0)
        assert rs.evaluation(i).rows == ev.rows
        ratio = 1.0 - ev.column("eta_rail_acc_max")
        assert table["ratio_rail_acc_max"][i] == pytest.approx(np.quantile(ratio, 0.9))
        assert table["sem_rail_acc_max"][i] == pytest.approx(ratio.std(ddof=1) / 2)
    at70 = rs.table("mean", speed=70.0)
    best = rs.best("mean", speed=70.0)
    pool = np.flatnonzero(at70["feasible"]) if at70["feasible"].any() else np.arange(2)
    assert best["ratio_rail_acc_max"] == at70["ratio_rail_acc_max"][pool].min()
    # a re-run resumes from the journals without running anything
    again = vtb.sweep(cfg, [2.0, 5.0], [2e8], [1e3], samples=2, speeds=[70.0, 80.0], out=tmp_path, progress=False)
    assert again.evaluation(1).rows == rs.evaluation(1).rows


def test_robust_optimisation_ranks_designs_by_the_statistic_over_the_cases():
    cfg = _config()
    speeds = [70.0, 80.0]
    rs = vtb.sweep(cfg, [2.0, 5.0], [1e8, 2e8], [1e3], samples=2, speeds=speeds, progress=False)
    res = vtb.optimize(cfg, samples=2, speeds=speeds, statistic="max", pop_size=6, n_gen=2, warm_start=rs, progress=False)
    assert isinstance(res, robust.RobustOptimizationResult) and len(res) >= 1
    assert sorted(res.baseline) == [(v, s) for v in speeds for s in (1000, 1001)]
    # every design on the front: its objectives are the statistic of its cases, recomputed by
    # the out-of-sample evaluator (itself checked against single runs above)
    for i in range(len(res)):
        d = {k: float(res.pareto[k][i]) for k in ("b_t", "k_t", "c_t")}
        ev = vtb.evaluate_design(cfg, d, samples=2, speeds=speeds, first_seed=robust.DESIGN_SEED0)
        F, G = robust.robust_objectives(ev.rows, "max")
        assert res.pareto["ratio_rail_acc_max"][i] == pytest.approx(F[0]) and res.pareto["ratio_slab_acc_max"][i] == pytest.approx(F[1])
        assert max(G) <= 0.0  # the returned set is feasible under the statistic's constraints
    # the hypervolume is that of the front in (ratio_rail, ratio_slab) against (1, 1)
    F = np.column_stack([res.pareto["ratio_rail_acc_max"], res.pareto["ratio_slab_acc_max"]])
    assert res.moga.history[-1].hypervolume == pytest.approx(vtb.optim.hypervolume_2d(F, (1.0, 1.0)))
    # per-speed optimum: the brute-force minimum over every evaluated design
    for v in speeds:
        t = res.evaluated_table(speed=v)
        ok = np.flatnonzero(t["feasible"])
        if ok.size:
            assert res.best(speed=v)["ratio_rail_acc_max"] == t["ratio_rail_acc_max"][ok].min()


def test_robust_studies_refuse_what_they_cannot_do():
    cfg = _config()
    with pytest.raises(vtb.ConfigError) as e:
        vtb.sweep(cfg, [5.0], [2e8], [1e3], samples=2, statistic="p100", progress=False)
    assert e.value.field == "statistic"
    with pytest.raises(vtb.ConfigError) as e:
        vtb.optimize(cfg, samples=2, statistic="worst", pop_size=4, n_gen=1, progress=False)
    assert e.value.field == "statistic"
    rs = vtb.sweep(cfg, [5.0], [2e8], [1e3], samples=1, progress=False)
    with pytest.raises(vtb.ConfigError) as e:
        vtb.optimize(cfg, samples=2, warm_start=rs, pop_size=4, n_gen=1, progress=False)
    assert e.value.field == "warm_start"


def test_the_timoshenko_pinned_pinned_frequency_is_the_beam_equations_root():
    from vtb.config.resolution import pinned_pinned_frequency

    article, conv = vtb.paper_config(), vtb.paper_config(model="converged")
    f_eb, f_t = pinned_pinned_frequency(article), pinned_pinned_frequency(conv)
    assert f_eb == pytest.approx(1282.4, abs=0.1)  # (π/d)²·sqrt(EI/ρA)/2π, d = 0.64 m
    rail = conv.structure.layers[0]
    w = 2 * math.pi * f_t
    k = math.pi / 0.64
    kg = rail.shear_coefficient * rail.shear_modulus
    E, I, rho, A = rail.youngs_modulus, rail.inertia, rail.density, rail.area
    residual = rho**2 * I / kg * w**4 - (rho * A + rho * I * k * k * (1 + E / kg)) * w**2 + E * I * k**4
    assert abs(residual) < 1e-9 * E * I * k**4
    assert 950 < f_t < 1010  # ≈ 1 kHz, as measured on tracks with 0.64 m bays


def test_a_resumed_robust_optimisation_runs_nothing_and_knows_every_design(tmp_path, monkeypatch):
    cfg = _config()
    rs = vtb.sweep(cfg, [5.0], [1e8, 2e8], [1e3], samples=2, progress=False)
    kw = dict(samples=2, pop_size=4, n_gen=2, warm_start=rs, checkpoint=tmp_path / "r.npz", progress=False)
    first = vtb.optimize(cfg, **kw)
    assert len(first.evaluated) > len(rs.designs)  # the optimiser ran designs of its own

    def no_runs(*a, **k):
        raise AssertionError("a resumed, finished optimisation must not run anything")

    monkeypatch.setattr(scaleout, "simulate_batch", no_runs)
    again = vtb.optimize(cfg, **kw)
    assert again.evaluated.keys() == first.evaluated.keys()
    assert all(again.evaluated[k] == first.evaluated[k] for k in first.evaluated)
    assert again.best() == first.best()
