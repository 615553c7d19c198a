"""Studies over any field and any index (vtb.study, vtb.optimize(variables=...)): each case is
the run of a configuration built by hand, the article's sweep and optimisation are presets of the
generic ones (same results), an interrupted study resumes without running a finished case again,
and bad input names the field."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vtb
from conftest import short_case
from vtb.studies import grid as studies_mod
from vtb.article.tid_problem import ARTICLE_CONSTRAINTS, ARTICLE_VARIABLES
from vtb.run.indices import ARTICLE_OBJECTIVES, METRICS


@pytest.fixture(scope="module")
def short():
    """The shared short case at 0.1 s."""
    return short_case(0.1)


GRID = {"speed": [70.0, 80.0], "structure.couplings[0].stiffness": [4e7, 6e7]}
INDICES = ["rail_acc_max", "slab_disp_max", "contact_force_max"]


@pytest.fixture(scope="module")
def grid_study(short):
    return vtb.study(short, GRID, indices=INDICES, progress=False)


def test_each_case_is_the_run_of_its_configuration_built_by_hand(short, grid_study):
    c = grid_study.columns
    assert list(c["case"]) == [1, 2, 3, 4] and grid_study.variables == tuple(GRID) and grid_study.indices == tuple(INDICES)
    for i, (v, k) in enumerate((v, k) for v in GRID["speed"] for k in GRID["structure.couplings[0].stiffness"]):
        cfg = short.copy()
        cfg.speed = v
        cfg.structure.couplings[0] = dataclasses.replace(cfg.structure.couplings[0], stiffness=k)
        m = vtb.simulate(cfg).metrics()
        assert (c["speed"][i], c["structure.couplings[0].stiffness"][i]) == (v, k)
        for name in INDICES:
            assert c[name][i] == m[name], (i, name)
    assert set(grid_study.to_pandas().columns) == {"case", *GRID, *INDICES, "error"}


def test_the_article_sweep_is_a_preset_of_the_study(short):
    grid = dict(b_t=[2.0, 5.0], k_t=[1e8, 2e8], c_t=[1e3])
    sweep = vtb.sweep(short, **grid, progress=False)
    generic = vtb.study(short, {"tids.b_t": grid["b_t"], "tids.k_t": grid["k_t"], "tids.c_t": grid["c_t"]},
                        reference={"tids": None}, indices=list(METRICS), progress=False)
    assert list(generic.columns["case"]) == list(sweep.columns["case"])
    for short_name, path in (("b_t", "tids.b_t"), ("k_t", "tids.k_t"), ("c_t", "tids.c_t")):
        np.testing.assert_array_equal(generic.columns[path], sweep.columns[short_name])
    for m in METRICS:
        np.testing.assert_array_equal(generic.columns[m], sweep.columns[m])
    # and the sweep's cases are the runs of the dampers set by hand
    cfg = short.copy()
    cfg.tids = dataclasses.replace(cfg.tids, inertance=5.0, stiffness=2e8, damping=1e3)
    assert sweep.columns["rail_acc_max"][4] == vtb.simulate(cfg).metrics()["rail_acc_max"]
    assert generic.reference == sweep.baseline


def test_the_article_optimisation_is_a_preset_of_the_generic_one(short):
    article = vtb.optimize(short, pop_size=6, n_gen=2, seed=3, progress=False)
    generic = vtb.optimize(short, variables=ARTICLE_VARIABLES, objectives=list(ARTICLE_OBJECTIVES), constraints=list(ARTICLE_CONSTRAINTS),
                           reference={"tids": None}, report=list(METRICS), pop_size=6, n_gen=2, seed=3, progress=False)
    np.testing.assert_array_equal(article.moga.X, generic.moga.X)
    np.testing.assert_array_equal(article.moga.F, generic.moga.F)
    assert len(article) == len(generic)
    for short_name, path in (("b_t", "tids.b_t"), ("k_t", "tids.k_t"), ("c_t", "tids.c_t")):
        np.testing.assert_array_equal(article.pareto[short_name], generic.pareto[path])
    for m in METRICS:
        np.testing.assert_array_equal(article.pareto[m], generic.pareto[m])
    assert {m: generic.reference[m] for m in article.baseline} == article.baseline


def test_an_optimisation_over_other_fields_returns_feasible_designs_of_their_own_runs(short):
    r = vtb.optimize(short, variables={"tids.stiffness": (1e7, 8e8, "log"), "speed": (60.0, 90.0)},
                     objectives=["rail_acc_max", "slab_acc_max"], constraints=[("contact_force_max", 1.2e5)],
                     report=["car_acc_max"], pop_size=6, n_gen=2, seed=1, progress=False)
    assert len(r) >= 1 and r.reference is None
    F = np.column_stack([r.pareto["rail_acc_max"], r.pareto["slab_acc_max"]])
    for i in range(len(r)):
        cfg = short.copy()
        cfg.tids = dataclasses.replace(cfg.tids, stiffness=float(r.pareto["tids.stiffness"][i]))
        cfg.speed = float(r.pareto["speed"][i])
        m = vtb.simulate(cfg).metrics()
        for name in ("rail_acc_max", "slab_acc_max", "contact_force_max", "car_acc_max"):
            assert r.pareto[name][i] == m[name]
        assert m["contact_force_max"] <= 1.2e5
        assert 1e7 <= cfg.tids.stiffness <= 8e8 and 60.0 <= cfg.speed <= 90.0
        assert not any(np.all(F[j] <= F[i]) and np.any(F[j] < F[i]) for j in range(len(r)))  # none dominated


def test_an_interrupted_study_resumes_without_running_a_finished_case(short, grid_study, tmp_path, monkeypatch):
    out = tmp_path / "study.csv"
    real = studies_mod.run_cases

    def interrupted(configs, on_result, **kw):
        seen = []

        def stop_after_two(i, r):
            on_result(i, r)
            seen.append(i)
            if len(seen) == 2:
                raise KeyboardInterrupt

        real(configs, stop_after_two, **kw)

    monkeypatch.setattr(studies_mod, "run_cases", interrupted)
    with pytest.raises(KeyboardInterrupt):
        vtb.study(short, GRID, indices=INDICES, out=out, progress=False, threads=1)
    ran = []

    def recording(configs, on_result, **kw):
        ran.extend((c.speed, c.structure.couplings[0].stiffness) for c in configs)
        real(configs, on_result, **kw)

    monkeypatch.setattr(studies_mod, "run_cases", recording)
    resumed = vtb.study(short, GRID, indices=INDICES, out=out, progress=False)
    assert len(ran) == 2
    for k in ("case", *GRID, *INDICES):
        np.testing.assert_array_equal(resumed.columns[k], grid_study.columns[k])
    ran.clear()
    vtb.study(short, GRID, indices=INDICES, out=out, progress=False)
    assert ran == []
    with pytest.raises(vtb.ConfigError, match="out"):  # another study's columns on this journal
        vtb.study(short, GRID, indices=["rail_acc_max"], out=out, progress=False)


def test_integer_fields_take_integral_values(short):
    cfg = short.copy()
    vtb.set_field(cfg, "irregularity.seed", 7.0)
    assert cfg.irregularity.seed == 7 and isinstance(cfg.irregularity.seed, int)
    vtb.set_field(cfg, "tids.k_t", 3e8)
    assert cfg.tids.stiffness == 3e8 and vtb.get_field(cfg, "tids.stiffness") == 3e8


@pytest.mark.parametrize("grid, kw, field", [
    ({"structure.coupling[0].stiffness": [1.0]}, {}, "structure.coupling"),
    ({"structure.couplings[9].stiffness": [1.0]}, {}, "couplings[9]"),
    ({"speed..x": [1.0]}, {}, "speed..x"),
    ({"speed": []}, {}, "speed"),
    ({"speed": [math.nan]}, {}, "speed"),
    ({"speed": ["fast"]}, {}, "speed"),
    ({"speed": [80.0]}, {"indices": ["rail_acc_peak"]}, "indices"),
    ({"speed": [300.0 / 3.6 * 10]}, {}, "speed"),  # implausible: the core's check names it
    ({}, {}, "grid"),
])
def test_bad_study_input_names_the_field(short, grid, kw, field):
    with pytest.raises(vtb.ConfigError, match=field.replace("[", r"\[").replace(".", r"\.")):
        vtb.study(short, grid, progress=False, **kw)


@pytest.mark.parametrize("kw, field", [
    (dict(variables={"speed": (60.0, 90.0, "cubic")}, objectives=["rail_acc_max"]), "speed"),
    (dict(variables={"speed": (90.0, 60.0)}, objectives=["rail_acc_max"]), "speed"),
    (dict(variables={"tids.k_t": (0.0, 1e8, "log")}, objectives=["rail_acc_max"]), "tids.k_t"),
    (dict(variables={"tids.q_t": (1.0, 2.0)}, objectives=["rail_acc_max"]), "tids.q_t"),
    (dict(variables={"speed": (60.0, 90.0)}, objectives=["rail_acc_peak"]), "objectives"),
    (dict(variables={"speed": (60.0, 90.0)}, objectives=["rail_acc_max"], constraints=[("rail_acc_max", "reference")]), "reference"),
    (dict(variables={"speed": (60.0, 90.0)}, objectives=["rail_acc_max"], constraints=[("rail_acc_max", math.inf)]), "constraints"),
    (dict(objectives=["rail_acc_max"]), "variables"),
])
def test_bad_optimisation_input_names_the_field(short, kw, field):
    with pytest.raises(vtb.ConfigError, match=field.replace("[", r"\[").replace(".", r"\.")):
        vtb.optimize(short, pop_size=4, n_gen=1, progress=False, **kw)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=30))
def test_any_text_as_a_path_is_a_field_or_a_config_error(path):
    cfg = vtb.paper_config()
    try:
        vtb.get_field(cfg, path)
    except vtb.ConfigError:
        pass


def test_ride_comfort_is_a_core_index_equal_to_vtb_comfort(short):
    """car_comfort_aw (ISO 2631-1 a_w, computed in the core) against vtb.comfort's SciPy filter
    on the same record, over the whole run and over a window; a study can name it."""
    import warnings

    cfg = short.copy()
    cfg.tids = None
    r = vtb.simulate(cfg)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", vtb.analysis.comfort.ComfortWarning)
        whole = r.comfort()["a_w"]
        part = r.comfort(window=(0.020025, 0.090025))["a_w"]
    assert r.metrics()["car_comfort_aw"] == pytest.approx(whole, rel=1e-8)
    cfg.output.window = [0.020025, 0.090025]
    assert vtb.simulate(cfg).metrics()["car_comfort_aw"] == pytest.approx(part, rel=1e-8)
    s = vtb.study(short, {"speed": [80.0]}, indices=["car_comfort_aw", "bridge_acc_max"], progress=False)
    one = vtb.simulate(short).metrics()
    assert s.columns["car_comfort_aw"][0] == one["car_comfort_aw"] and s.columns["bridge_acc_max"][0] == one["bridge_acc_max"]
    assert vtb.metric_unit("car_comfort_aw") == "m/s²"
